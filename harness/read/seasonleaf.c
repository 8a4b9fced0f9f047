/* sere harness — the seed-002 leaf: key points → B-spline → Delaunay → mesh optimization →
 * masses from the mask (Tang Eq. 3) → deformation levels by the mass-spring model (Sec. 4). */
#include "read/seasonleaf.h"

#include "common/io.h"
#include "common/params.h"
#include "core/array.h"
#include "mesh/bspline.h"
#include "mesh/meshopt.h"
#include "mesh/triangulate.h"
#include "read/leafimage.h"
#include "season/massspring.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MAX_KEYS 100000
#define MAX_SIDE 8192
/* Key points taken from a traced silhouette, as a user would click them (the keys file has 66). */
#define SILHOUETTE_KEYS 64
/* Mass range of Tang Eq. 3 (massspring.h's units: the leaf about 1 long). */
#define MASS_MIN 0.1f
#define MASS_MAX 1.0f
/* The cup of the rest shape (massspring.h: it picks the side the blade curls to), as a height at
 * unit distance from the blade's centroid. A flatter rest shape lets the contracting flexion
 * springs buckle the blade either way, in crinkles instead of one curl. */
#define REST_CUP 0.25f
/* The drying of the most withered level: structural springs contract by SHRINK_MAX and flexion
 * springs by CURL_MAX, levels in between in proportion. Seed 002's Fig. 4 shows a blade that cups,
 * droops and finally crinkles; these values give that on the maple (docs/season-leaf.png). */
#define SHRINK_MAX 0.05f
#define CURL_MAX   0.3f

sere_season_leaf_options sere_season_leaf_options_default( void )
{
	return ( sere_season_leaf_options ){
		.keys_path = "seasons/maple.keys",
		.silhouette_path = NULL,
		.mask_path = "masks/maple.pgm",
		.outline_samples = 120,
		.meshopt_iterations = 160,
		.levels = 4,
		.steps_per_level = 400,
	};
}

/* The key points file: '#' comments, "image W H" first, then "x y" pixel positions. */
static sere_status read_keys( const char* path, double** xy, int32_t* count, int32_t* width, int32_t* height, char* err,
							  size_t err_size )
{
	FILE* f = fopen( path, "r" );
	if ( f == NULL )
	{
		return sere_fail( SERE_ERR_ARGUMENT, err, err_size, "%s: cannot open: %s", path, strerror( errno ) );
	}
	char line[512];
	int line_number = 0, have_image = 0;
	int32_t n = 0, capacity = 0;
	double* points = NULL;
	sere_status status = SERE_OK;
	while ( status == SERE_OK && fgets( line, sizeof( line ), f ) != NULL )
	{
		line_number += 1;
		char* hash = strchr( line, '#' );
		if ( hash != NULL )
		{
			*hash = '\0';
		}
		char word[32];
		if ( sscanf( line, "%31s", word ) != 1 )
		{
			continue;
		}
		char extra[2];
		if ( strcmp( word, "image" ) == 0 )
		{
			int w, h;
			if ( have_image || sscanf( line, " image %d %d %1s", &w, &h, extra ) != 2 || w < 2 || h < 2 ||
				 w > MAX_SIDE || h > MAX_SIDE )
			{
				status =
					sere_fail( SERE_ERR_ARGUMENT, err, err_size, "%s:%d: expected one 'image W H' with 2 <= W, H <= %d",
							   path, line_number, MAX_SIDE );
				break;
			}
			have_image = 1, *width = w, *height = h;
			continue;
		}
		double x, y;
		if ( sscanf( line, "%lf %lf %1s", &x, &y, extra ) != 2 )
		{
			status = sere_fail( SERE_ERR_ARGUMENT, err, err_size, "%s:%d: expected 'x y' (two numbers) or 'image W H'",
								path, line_number );
		}
		else if ( !have_image )
		{
			status = sere_fail( SERE_ERR_ARGUMENT, err, err_size, "%s:%d: 'image W H' must come before the points",
								path, line_number );
		}
		else if ( !isfinite( x ) || !isfinite( y ) || x < 0.0 || y < 0.0 || x > *width || y > *height )
		{
			status = sere_fail( SERE_ERR_ARGUMENT, err, err_size, "%s:%d: point (%g, %g) outside the %d x %d image",
								path, line_number, x, y, *width, *height );
		}
		else if ( n == MAX_KEYS )
		{
			status = sere_fail( SERE_ERR_ARGUMENT, err, err_size, "%s:%d: more than %d key points", path, line_number,
								MAX_KEYS );
		}
		else
		{
			if ( n == capacity )
			{
				capacity = sere_array_capacity( capacity, (int64_t) n + 1, 64 );
				double* grown = capacity > 0 ? sere_array_resize( points, capacity, 2 * sizeof( double ) ) : NULL;
				if ( grown == NULL )
				{
					status = sere_fail( SERE_ERR_MEMORY, err, err_size, "%s: out of memory", path );
					break;
				}
				points = grown;
			}
			points[2 * n] = x, points[2 * n + 1] = y;
			n += 1;
		}
	}
	fclose( f );
	if ( status == SERE_OK && n < 3 )
	{
		status = sere_fail( SERE_ERR_ARGUMENT, err, err_size, "%s: %d key points; a leaf needs at least 3", path, n );
	}
	if ( status != SERE_OK )
	{
		free( points );
		return status;
	}
	*xy = points;
	*count = n;
	return SERE_OK;
}

/* Every tenth-ish point of a traced silhouette, at even arc length, point 0 kept. */
static double* pick_keys( const double* xy, int32_t n, int32_t* count )
{
	double* keys = malloc( sizeof( double ) * 2 * SILHOUETTE_KEYS );
	double* along = malloc( sizeof( double ) * ( (size_t) n + 1 ) );
	if ( keys == NULL || along == NULL )
	{
		free( keys ), free( along );
		return NULL;
	}
	along[0] = 0.0;
	for ( int32_t i = 0; i < n; ++i )
	{
		int32_t j = ( i + 1 ) % n;
		along[i + 1] = along[i] + hypot( xy[2 * j] - xy[2 * i], xy[2 * j + 1] - xy[2 * i + 1] );
	}
	int32_t segment = 0;
	for ( int32_t k = 0; k < SILHOUETTE_KEYS; ++k )
	{
		double s = along[n] * k / SILHOUETTE_KEYS;
		while ( along[segment + 1] < s )
		{
			segment += 1;
		}
		int32_t j = ( segment + 1 ) % n;
		double span = along[segment + 1] - along[segment];
		double t = span > 0.0 ? ( s - along[segment] ) / span : 0.0;
		keys[2 * k] = xy[2 * segment] + t * ( xy[2 * j] - xy[2 * segment] );
		keys[2 * k + 1] = xy[2 * segment + 1] + t * ( xy[2 * j + 1] - xy[2 * segment + 1] );
	}
	free( along );
	*count = SILHOUETTE_KEYS;
	return keys;
}

/* A binary PGM (P5, maxval ≤ 65535) as gray in [0, 1], row 0 at the top. */
static sere_status read_pgm( const char* path, float** gray, int32_t* width, int32_t* height, char* err,
							 size_t err_size )
{
	FILE* f = fopen( path, "rb" );
	if ( f == NULL )
	{
		return sere_fail( SERE_ERR_ARGUMENT, err, err_size, "%s: cannot open: %s", path, strerror( errno ) );
	}
	long header[3];
	char magic[3] = { 0 };
	int ok = fread( magic, 1, 2, f ) == 2 && magic[0] == 'P' && magic[1] == '5';
	for ( int k = 0; ok && k < 3; ++k )
	{
		int c = fgetc( f );
		while ( c == '#' || c == ' ' || c == '\t' || c == '\n' || c == '\r' )
		{
			if ( c == '#' )
			{
				while ( c != '\n' && c != EOF )
				{
					c = fgetc( f );
				}
			}
			c = fgetc( f );
		}
		ungetc( c, f );
		ok = fscanf( f, "%ld", &header[k] ) == 1;
	}
	/* one whitespace byte ends the header; anything else is not the P5 layout */
	int separator = ok ? fgetc( f ) : EOF;
	if ( !ok || ( separator != ' ' && separator != '\t' && separator != '\n' && separator != '\r' ) )
	{
		fclose( f );
		return sere_fail( SERE_ERR_ARGUMENT, err, err_size, "%s: not a binary PGM (P5) image", path );
	}
	if ( header[0] < 1 || header[1] < 1 || header[0] > MAX_SIDE || header[1] > MAX_SIDE || header[2] < 1 ||
		 header[2] > 65535 )
	{
		fclose( f );
		return sere_fail( SERE_ERR_ARGUMENT, err, err_size,
						  "%s: bad PGM header %ld x %ld, maxval %ld (at most %d x %d, 65535)", path, header[0],
						  header[1], header[2], MAX_SIDE, MAX_SIDE );
	}
	const int32_t w = (int32_t) header[0], h = (int32_t) header[1];
	const size_t n = (size_t) w * (size_t) h, bytes = header[2] > 255 ? 2 : 1;
	uint8_t* raw = malloc( n * bytes );
	float* g = malloc( n * sizeof( float ) );
	if ( raw == NULL || g == NULL )
	{
		fclose( f );
		free( raw ), free( g );
		return sere_fail( SERE_ERR_MEMORY, err, err_size, "%s: out of memory for %d x %d pixels", path, w, h );
	}
	size_t got = fread( raw, bytes, n, f );
	fclose( f );
	if ( got != n )
	{
		free( raw ), free( g );
		return sere_fail( SERE_ERR_ARGUMENT, err, err_size, "%s: truncated: %zu of %zu pixels", path, got, n );
	}
	for ( size_t i = 0; i < n; ++i )
	{
		unsigned value = bytes == 2 ? ( (unsigned) raw[2 * i] << 8 ) | raw[2 * i + 1] : raw[i];
		if ( value > (unsigned long) header[2] )
		{
			free( raw ), free( g );
			return sere_fail( SERE_ERR_ARGUMENT, err, err_size, "%s: pixel (%zu, %zu) is %u, above the maxval %ld",
							  path, i % (size_t) w, i / (size_t) w, value, header[2] );
		}
		g[i] = (float) ( (double) value / (double) header[2] );
	}
	free( raw );
	*gray = g, *width = w, *height = h;
	return SERE_OK;
}

static int has_suffix( const char* s, const char* suffix )
{
	size_t n = strlen( s ), m = strlen( suffix );
	return n >= m && strcmp( s + n - m, suffix ) == 0;
}

/* Bilinear lookup with pixel centres at (i + 1/2, j + 1/2), clamped at the image border. */
static float sample_gray( const float* gray, int32_t w, int32_t h, double px, double py )
{
	double fx = fmin( fmax( px - 0.5, 0.0 ), w - 1.0 ), fy = fmin( fmax( py - 0.5, 0.0 ), h - 1.0 );
	int32_t i = (int32_t) fx, j = (int32_t) fy;
	int32_t i1 = i + 1 < w ? i + 1 : i, j1 = j + 1 < h ? j + 1 : j;
	double tx = fx - i, ty = fy - j;
	double top = ( 1.0 - tx ) * gray[j * w + i] + tx * gray[j * w + i1];
	double bottom = ( 1.0 - tx ) * gray[j1 * w + i] + tx * gray[j1 * w + i1];
	return (float) ( ( 1.0 - ty ) * top + ty * bottom );
}

void sere_season_leaf_destroy( sere_season_leaf* leaf )
{
	if ( leaf == NULL )
	{
		return;
	}
	free( leaf->tri ), free( leaf->u ), free( leaf->v ), free( leaf->mass ), free( leaf->xyz );
	memset( leaf, 0, sizeof( *leaf ) );
}

/* The deformation levels (Sec. 4, Fig. 4): level 0 the flat blade; from a slightly cupped rest
 * shape the mass-spring model runs steps_per_level steps per level with the springs contracted in
 * proportion to the level, held at the petiole and its ring of neighbours. */
static sere_status deform( sere_season_leaf* leaf, int32_t steps_per_level, int32_t threads, char* err,
						   size_t err_size )
{
	const int32_t n = leaf->vertex_count;
	float* buffer = calloc( 7 * (size_t) n, sizeof( float ) );
	if ( buffer == NULL )
	{
		return sere_fail( SERE_ERR_MEMORY, err, err_size, "leaf: out of memory for %d particles", n );
	}
	float *x = buffer, *y = x + n, *z = y + n, *vx = z + n, *vy = vx + n, *vz = vy + n, *inv_m = vz + n;
	double cx = 0.0, cy = 0.0;
	for ( int32_t i = 0; i < n; ++i )
	{
		x[i] = leaf->xyz[3 * i], y[i] = leaf->xyz[3 * i + 1];
		cx += x[i], cy += y[i];
	}
	cx /= n, cy /= n;
	for ( int32_t i = 0; i < n; ++i )
	{
		double dx = x[i] - cx, dy = y[i] - cy;
		z[i] = REST_CUP * (float) ( dx * dx + dy * dy );
		inv_m[i] = 1.0f / leaf->mass[i];
	}
	/* the petiole is vertex 0; it and its neighbours hold the blade's attitude */
	inv_m[0] = 0.0f;
	for ( int32_t t = 0; t < leaf->triangle_count; ++t )
	{
		const int32_t* q = leaf->tri + 3 * t;
		if ( q[0] == 0 || q[1] == 0 || q[2] == 0 )
		{
			inv_m[q[0]] = inv_m[q[1]] = inv_m[q[2]] = 0.0f;
		}
	}
	const float z0 = z[0];
	for ( int32_t i = 0; i < n; ++i )
	{
		z[i] -= z0;
	}
	sere_massspring* ms = NULL;
	sere_status status = sere_massspring_create( x, y, z, n, leaf->tri, leaf->triangle_count, &ms );
	status = status == SERE_OK ? sere_massspring_set_threads( ms, threads ) : status;
	if ( status != SERE_OK )
	{
		free( buffer );
		return sere_fail( status, err, err_size, "leaf: the optimized mesh cannot carry springs (%s)",
						  sere_status_text( status ) );
	}
	sere_massspring_particles particles = { n, x, y, z, vx, vy, vz, inv_m };
	sere_massspring_params params = sere_massspring_params_default();
	for ( int32_t level = 1; level < leaf->level_count && status == SERE_OK; ++level )
	{
		float share = (float) level / (float) ( leaf->level_count - 1 );
		params.shrink = SHRINK_MAX * share;
		params.curl = CURL_MAX * share;
		for ( int32_t step = 0; step < steps_per_level && status == SERE_OK; ++step )
		{
			status = sere_massspring_step( ms, &particles, &params, NULL );
			/* a step at the sweep cap is still taken; the next steps bring the springs back */
			status = status == SERE_ERR_NO_CONVERGE ? SERE_OK : status;
		}
		float* out = leaf->xyz + 3 * (size_t) n * (size_t) level;
		for ( int32_t i = 0; i < n; ++i )
		{
			out[3 * i] = x[i], out[3 * i + 1] = y[i], out[3 * i + 2] = z[i];
		}
	}
	sere_massspring_destroy( ms );
	free( buffer );
	return status == SERE_OK ? SERE_OK
							 : sere_fail( status, err, err_size, "leaf: the mass-spring model failed (%s)",
										  sere_status_text( status ) );
}

static sere_status check_options( const sere_season_leaf_options* options, char* err, size_t err_size )
{
	const struct
	{
		const char* what;
		int value, lo, hi;
	} ranges[] = {
		{ "outline samples", options->outline_samples, 8, 20000 },
		{ "mesh optimization iterations", options->meshopt_iterations, 0, 10000 },
		{ "deformation levels", options->levels, 1, 64 },
		{ "steps per level", options->steps_per_level, 0, 1000000 },
		{ "threads", options->threads, 0, SERE_MAX_THREADS },
	};
	for ( size_t k = 0; k < sizeof( ranges ) / sizeof( ranges[0] ); ++k )
	{
		if ( ranges[k].value < ranges[k].lo || ranges[k].value > ranges[k].hi )
		{
			return sere_fail( SERE_ERR_ARGUMENT, err, err_size, "%s: %d is outside [%d, %d]", ranges[k].what,
							  ranges[k].value, ranges[k].lo, ranges[k].hi );
		}
	}
	if ( ( options->keys_path == NULL ) == ( options->silhouette_path == NULL ) )
	{
		return sere_fail( SERE_ERR_ARGUMENT, err, err_size, "leaf: give key points or a silhouette, exactly one" );
	}
	if ( options->mask_path == NULL )
	{
		return sere_fail( SERE_ERR_ARGUMENT, err, err_size, "leaf: no mask map" );
	}
	return SERE_OK;
}

/* Pixels (y down) to leaf units (y up): the petiole (key point 0) at the origin, the leaf 1 long
 * (the largest distance from the petiole to a key point), counter-clockwise with the petiole
 * staying first. Frees keys; -1 when out of memory. */
static int to_leaf_units( double* keys, int32_t key_count, double** kx_out, double** ky_out, double* base_x,
						  double* base_y, double* scale_out, double* twice_area_out )
{
	const double base_px = keys[0], base_py = keys[1];
	double scale = 0.0, twice_area = 0.0;
	for ( int32_t i = 0; i < key_count; ++i )
	{
		scale = fmax( scale, hypot( keys[2 * i] - base_px, keys[2 * i + 1] - base_py ) );
	}
	double* kx = malloc( sizeof( double ) * (size_t) key_count );
	double* ky = malloc( sizeof( double ) * (size_t) key_count );
	if ( kx == NULL || ky == NULL )
	{
		free( keys ), free( kx ), free( ky );
		return -1;
	}
	for ( int32_t i = 0; i < key_count; ++i )
	{
		kx[i] = ( keys[2 * i] - base_px ) / scale;
		ky[i] = ( base_py - keys[2 * i + 1] ) / scale;
	}
	free( keys );
	for ( int32_t i = 0, j = key_count - 1; i < key_count; j = i++ )
	{
		twice_area += kx[j] * ky[i] - kx[i] * ky[j];
	}
	/* counter-clockwise, the petiole staying first */
	for ( int32_t i = 1, j = key_count - 1; twice_area < 0.0 && i < j; ++i, --j )
	{
		double t = kx[i];
		kx[i] = kx[j], kx[j] = t;
		t = ky[i];
		ky[i] = ky[j], ky[j] = t;
	}
	*kx_out = kx, *ky_out = ky;
	*base_x = base_px, *base_y = base_py;
	*scale_out = scale, *twice_area_out = twice_area;
	return 0;
}

/* The leaf's arrays from the optimized mesh: triangles, texture coordinates in the image
 * (frame: the petiole's pixel x, y, pixels per leaf unit, image width, height), rest positions
 * and masses from the mask's gray under each vertex (Tang Eq. 3). */
static sere_status fill_leaf( sere_season_leaf* leaf, const sere_meshopt_mesh* m, int32_t levels, const float* gray,
							  int32_t mask_w, int32_t mask_h, const double frame[6], const char* mask, char* err,
							  size_t err_size )
{
	const double base_px = frame[0], base_py = frame[1], scale = frame[2], width = frame[3], height = frame[4];
	const int32_t n = m->vertex_count;
	leaf->vertex_count = n;
	leaf->triangle_count = m->triangle_count;
	leaf->level_count = levels;
	leaf->tri = malloc( sizeof( int32_t ) * 3 * (size_t) m->triangle_count );
	leaf->u = malloc( sizeof( float ) * (size_t) n );
	leaf->v = malloc( sizeof( float ) * (size_t) n );
	leaf->mass = malloc( sizeof( float ) * (size_t) n );
	leaf->xyz = calloc( 3 * (size_t) n * (size_t) levels, sizeof( float ) );
	float* vertex_gray = malloc( sizeof( float ) * (size_t) n );
	if ( leaf->tri == NULL || leaf->u == NULL || leaf->v == NULL || leaf->mass == NULL || leaf->xyz == NULL ||
		 vertex_gray == NULL )
	{
		free( vertex_gray );
		return sere_fail( SERE_ERR_MEMORY, err, err_size, "leaf: out of memory for %d vertices", n );
	}
	memcpy( leaf->tri, m->tri, sizeof( int32_t ) * 3 * (size_t) m->triangle_count );
	for ( int32_t i = 0; i < n; ++i )
	{
		double px = base_px + m->x[i] * scale, py = base_py - m->y[i] * scale;
		leaf->u[i] = (float) ( px / width );
		leaf->v[i] = (float) ( 1.0 - py / height );
		vertex_gray[i] = sample_gray( gray, mask_w, mask_h, px, py );
		leaf->xyz[3 * i] = (float) m->x[i];
		leaf->xyz[3 * i + 1] = (float) m->y[i];
	}
	sere_status status = sere_massspring_mass_from_gray( vertex_gray, n, MASS_MIN, MASS_MAX, leaf->mass );
	free( vertex_gray );
	if ( status != SERE_OK )
	{
		return sere_fail( status, err, err_size, "%s: the mask gives no masses (%s)", mask,
						  sere_status_text( status ) );
	}
	return SERE_OK;
}

/* The outline as a mesh: the closed B-spline through the key points sampled evenly into sx, sy,
 * triangulated, and optimized with triangles of the boundary's spacing. */
static sere_status outline_mesh( const double* kx, const double* ky, int32_t key_count, int32_t samples, double area,
								 int32_t iterations, const char* source, sere_bspline* spline, double* sx, double* sy,
								 sere_triangulation* triangulation, sere_meshopt** mo, char* err, size_t err_size )
{
	sere_status status = sere_bspline_fit( kx, ky, key_count, spline );
	if ( status != SERE_OK )
	{
		sere_fail( status, err, err_size, "%s: the key points give no B-spline (%s: two consecutive points equal?)",
				   source, sere_status_text( status ) );
		return status;
	}
	status = sere_bspline_sample( spline, samples, sx, sy, NULL );
	if ( status == SERE_OK )
	{
		/* sample 0 is key point 0, the petiole, up to the rounding of the spline's solve: make it
		 * exact, so the leaf hangs from the origin */
		sx[0] = kx[0], sy[0] = ky[0];
		sere_cdt_input input = { sx, sy, samples, samples, NULL, 0 };
		status = sere_triangulate( &input, triangulation );
	}
	if ( status != SERE_OK || triangulation->merged_count > 0 )
	{
		status = status != SERE_OK ? status : SERE_ERR_GEOMETRY;
		sere_fail( status, err, err_size,
				   "%s: the B-spline through the key points crosses itself at %d samples; move the key points apart or "
				   "sample more",
				   source, samples );
		return status;
	}
	/* edge length of the even outline sampling: the triangles aim at the boundary's spacing */
	const double h = spline->length / samples;
	int64_t capacity = 4 * (int64_t) ( area / ( h * h ) ) + 4 * (int64_t) samples + 64;
	if ( capacity > SERE_MESHOPT_MAX_VERTICES )
	{
		status = SERE_ERR_CAPACITY;
		sere_fail( status, err, err_size, "outline samples: %d samples would make more than %d vertices", samples,
				   SERE_MESHOPT_MAX_VERTICES );
		return status;
	}
	status = sere_meshopt_create( (int32_t) capacity, mo );
	if ( status == SERE_OK )
	{
		sere_meshopt_params mp = sere_meshopt_params_default( h );
		mp.iterations = iterations;
		status = sere_meshopt_run( *mo, sx, sy, samples, samples, triangulation->tri, triangulation->triangle_count,
								   &mp, NULL );
	}
	if ( status != SERE_OK )
	{
		sere_fail( status, err, err_size, "%s: mesh optimization failed (%s)", source, sere_status_text( status ) );
		return status;
	}
	return status;
}

sere_status sere_season_leaf_build( const sere_season_leaf_options* options, sere_season_leaf* leaf, char* err,
									size_t err_size )
{
	if ( err != NULL && err_size > 0 )
	{
		err[0] = '\0';
	}
	if ( options == NULL || leaf == NULL )
	{
		return sere_fail( SERE_ERR_ARGUMENT, err, err_size, "leaf: no options or no leaf to fill" );
	}
	memset( leaf, 0, sizeof( *leaf ) );
	sere_status status = check_options( options, err, err_size );
	if ( status != SERE_OK )
	{
		return status;
	}
	char keys_buffer[4096], mask_buffer[4096];
	double* keys = NULL;
	int32_t key_count = 0, width = 0, height = 0;
	const char* source;
	if ( options->keys_path != NULL )
	{
		source = sere_data_resolve( options->keys_path, keys_buffer, sizeof( keys_buffer ) );
		status = read_keys( source, &keys, &key_count, &width, &height, err, err_size );
	}
	else
	{
		source = sere_data_resolve( options->silhouette_path, keys_buffer, sizeof( keys_buffer ) );
		double* traced = NULL;
		int32_t traced_count = 0;
		status = sere_silhouette_from_png( source, &traced, &traced_count, &width, &height, err, err_size );
		if ( status == SERE_OK )
		{
			keys = pick_keys( traced, traced_count, &key_count );
			status = keys != NULL ? SERE_OK : sere_fail( SERE_ERR_MEMORY, err, err_size, "%s: out of memory", source );
			free( traced );
		}
	}
	if ( status != SERE_OK )
	{
		return status;
	}

	double base_px, base_py, scale, twice_area;
	double* kx = NULL;
	double* ky = NULL;
	if ( to_leaf_units( keys, key_count, &kx, &ky, &base_px, &base_py, &scale, &twice_area ) != 0 )
	{
		return sere_fail( SERE_ERR_MEMORY, err, err_size, "%s: out of memory", source );
	}

	sere_bspline spline = { 0 };
	const int32_t samples = options->outline_samples;
	double* sx = malloc( sizeof( double ) * (size_t) samples );
	double* sy = malloc( sizeof( double ) * (size_t) samples );
	sere_triangulation triangulation = { 0 };
	sere_meshopt* mo = NULL;
	float* gray = NULL;
	status = sx != NULL && sy != NULL
				 ? outline_mesh( kx, ky, key_count, samples, 0.5 * fabs( twice_area ), options->meshopt_iterations,
								 source, &spline, sx, sy, &triangulation, &mo, err, err_size )
				 : sere_fail( SERE_ERR_MEMORY, err, err_size, "%s: out of memory", source );
	if ( status != SERE_OK )
	{
		goto done;
	}
	sere_meshopt_mesh mesh = sere_meshopt_result( mo );

	int32_t mask_w = 0, mask_h = 0;
	const char* mask = sere_data_resolve( options->mask_path, mask_buffer, sizeof( mask_buffer ) );
	status = has_suffix( mask, ".png" ) || has_suffix( mask, ".PNG" )
				 ? sere_png_read_gray( mask, &gray, &mask_w, &mask_h, err, err_size )
				 : read_pgm( mask, &gray, &mask_w, &mask_h, err, err_size );
	if ( status != SERE_OK )
	{
		goto done;
	}
	if ( mask_w != width || mask_h != height )
	{
		status =
			sere_fail( SERE_ERR_ARGUMENT, err, err_size,
					   "%s: the mask is %d x %d pixels but the key points' image is %d x %d (one pixel frame for both)",
					   mask, mask_w, mask_h, width, height );
		goto done;
	}

	const double frame[6] = { base_px, base_py, scale, width, height, 0.0 };
	status = fill_leaf( leaf, &mesh, options->levels, gray, mask_w, mask_h, frame, mask, err, err_size );
	if ( status != SERE_OK )
	{
		goto done;
	}
	status = deform( leaf, options->steps_per_level, options->threads, err, err_size );

done:
	if ( status != SERE_OK )
	{
		sere_season_leaf_destroy( leaf );
	}
	free( gray );
	sere_meshopt_destroy( mo );
	sere_triangulation_destroy( &triangulation );
	sere_bspline_destroy( &spline );
	free( sx ), free( sy ), free( kx ), free( ky );
	return status;
}
