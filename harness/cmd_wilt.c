/* sere wilt — venation skeleton-based wilting of a leaf or a plant (seed 003: Lu, Zhao, Guo 2009):
 * skeleton file or parametric leaf → blade mesh → banding → frames of wilting, written as PLY, VTK
 * and PNG. */
#define _POSIX_C_SOURCE 200809L
#include "commands.h"
#include "io.h"
#include "params.h"
#include "skeleton.h"
#include "subdivide.h"
#include "topo.h"

#include <cairo.h>
#include <errno.h>
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define PI		  3.14159265358979323846
#define MAX_VEINS 256

static void wilt_help( void )
{
	printf(
		"usage: sere wilt [SKELETON] [options]\n\n"
		"Wilts a leaf, or a plant of leaves on a stem, with the venation skeleton method of Lu, Zhao & Guo\n"
		"(2009): the blade is meshed by constrained Delaunay triangulation and 1-to-4 subdivision, every vertex\n"
		"is banded to its nearest skeleton joint, and each joint turns its segment toward the downward vector\n"
		"with its children following, tips first; lower leaves start before upper ones.\n\n"
		"SKELETON is a skeleton file (a path, or a name in data/skeletons such as cucumber or watermelon); without\n"
		"it the parametric leaf of Sec. 4.1 is used.\n\n"
		"leaf:\n"
		"  --length L --width W --features K  parametric leaf: midvein length, blade width, feature points per\n"
		"                                     curve (default 10, 6, 9)\n"
		"  --spacing H       sampling interval of outline, midvein and interior (default leaf length / 25)\n"
		"  --subdivide K     1-to-4 subdivision passes (default 1)\n"
		"  --min-edge E      subdivision never makes edges shorter than E (default 0: cut every edge)\n"
		"venation (generated when the file has no 'vein' blocks):\n"
		"  --mid-segments N  joints along the midvein (default 20)\n"
		"  --veins N         secondary veins (default 8)\n"
		"  --vein-segments N joints along each secondary vein (default 8)\n"
		"  --vein-angle DEG  angle between secondary veins and the midvein (default 45)\n"
		"  --mid-bend DEG    total turn of the midvein at full wilting (default 80)\n"
		"  --vein-bend DEG   total turn of each secondary vein (default 50)\n"
		"wilting (Sec. 6):\n"
		"  --droop D         maximal drooped distance of any joint below its rest height (default: none)\n"
		"  --min-angle DEG   minimal included angle between adjacent segments of a vein (default 120)\n"
		"  --spread S        tip-to-base onset spread within a leaf, in [0, 1) (default 0.5)\n"
		"  --no-pierce       skip the piercing check (faster; the mesh may then pass through itself)\n"
		"plant (Sec. 7):\n"
		"  --leaves N        leaves up the stem, 137.5 degrees apart (default 1)\n"
		"  --stagger S       wilting onset of each leaf after the one below, in units of t (default 0.25)\n"
		"  --internode H     stem length between leaves (default 0.3 x leaf length)\n"
		"  --elevation DEG   rest angle of each midvein above horizontal (default 35)\n"
		"run:\n"
		"  --frames F        frames from t = 0 (default 40)\n"
		"  --speed S         increase of t per frame (default: the top leaf reaches t = 1 on the last frame)\n"
		"  --out DIR         write frame_NNNN.ply, frame_NNNN.vtp + wilt.pvd and frame_NNNN.png to DIR\n"
		"  --format LIST     comma-separated subset of ply,vtp,png (default ply,vtp,png)\n"
		"  --every K         write every K-th frame (the last frame always) (default 1)\n"
		"  --size WxH        picture size in pixels (default 800x600)\n"
		"  --view AZ,EL      picture view direction, degrees (default -70,25)\n"
		"  --threads T       OpenMP threads, 0 = one per core (default 0)\n"
		"  --json            print the summary as one JSON object\n\n"
		"Skeleton files are text: '#' starts a comment; keywords 'name NAME', 'left', 'right', 'midvein' and\n"
		"'vein PARENT SEGMENTS BEND_DEG' each start a block followed by 'x y' lines (leaf coordinates: base at\n"
		"the origin, midvein toward +x). left/right/midvein are the leaf skeleton's feature points from base to\n"
		"tip; each vein is a polyline, vein 0 the midvein with parent -1 (no points: it follows the midvein).\n" );
}

/* ------------------------------------------------------------------------------------------- */
/* Option parsing: one clear line and exit status 2 on a bad value. */

static int parse_pair( const char* option, const char* text, char separator, double lo, double hi, double* a,
					   double* b )
{
	char* end;
	*a = strtod( text, &end );
	if ( end != text && *end == separator )
	{
		const char* second = end + 1;
		*b = strtod( second, &end );
		if ( end != second && *end == '\0' && isfinite( *a ) && isfinite( *b ) && *a >= lo && *a <= hi && *b >= lo &&
			 *b <= hi )
		{
			return 0;
		}
	}
	fprintf( stderr, "sere wilt: %s takes two numbers 'A%cB' from %g to %g, not '%s'\n", option, separator, lo, hi,
			 text );
	return -1;
}

/* ------------------------------------------------------------------------------------------- */
/* Skeleton files. */

typedef struct point_list
{
	int32_t count, capacity;
	double* xy;
	int32_t* line; /* file line of each point, for messages */
} point_list;

typedef struct skeleton_file
{
	char path[4096];
	char name[64];
	point_list curve[3]; /* left, right, midvein */
	int32_t curve_line[3];
	int32_t vein_count;
	point_list vein[MAX_VEINS];
	int32_t vein_line[MAX_VEINS];
	int32_t vein_parent[MAX_VEINS];
	int32_t vein_segments[MAX_VEINS];
	double vein_bend[MAX_VEINS];
} skeleton_file;

static const char* const curve_names[3] = { "left boundary curve", "right boundary curve", "midvein" };

static void skeleton_file_free( skeleton_file* s )
{
	for ( int k = 0; k < 3; ++k )
	{
		free( s->curve[k].xy );
		free( s->curve[k].line );
	}
	for ( int32_t k = 0; k < s->vein_count; ++k )
	{
		free( s->vein[k].xy );
		free( s->vein[k].line );
	}
}

static int point_push( point_list* p, double x, double y, int32_t line )
{
	if ( p->count == p->capacity )
	{
		int32_t capacity = p->capacity > 0 ? 2 * p->capacity : 16;
		double* xy = realloc( p->xy, 2 * (size_t) capacity * sizeof( double ) );
		if ( xy == NULL )
		{
			return -1;
		}
		p->xy = xy;
		int32_t* lines = realloc( p->line, (size_t) capacity * sizeof( int32_t ) );
		if ( lines == NULL )
		{
			return -1;
		}
		p->line = lines;
		p->capacity = capacity;
	}
	p->xy[2 * p->count] = x;
	p->xy[2 * p->count + 1] = y;
	p->line[p->count++] = line;
	return 0;
}

/* Finds NAME as a path or as data/skeletons/NAME.skel. */
static int skeleton_locate( const char* name, char* path, size_t size )
{
	FILE* f = fopen( name, "r" );
	if ( f != NULL )
	{
		fclose( f );
		snprintf( path, size, "%s", name );
		return 0;
	}
	char relative[512];
	snprintf( relative, sizeof( relative ), "skeletons/%s.skel", name );
	return sere_data_path( relative, path, size );
}

/* A 'vein PARENT SEGMENTS BEND_DEGREES' line: opens the vein's block. */
static int skeleton_vein_line( skeleton_file* s, const char* rest, int32_t number, point_list** block, char* err,
							   size_t err_size )
{
	long parent, segments;
	double bend;
	char extra[8];
	if ( sscanf( rest, " %ld %ld %lf %7s", &parent, &segments, &bend, extra ) != 3 || !isfinite( bend ) )
	{
		snprintf( err, err_size, "%s:%d: 'vein' takes PARENT SEGMENTS BEND_DEGREES, e.g. 'vein 0 6 60'", s->path,
				  number );
		return -1;
	}
	if ( s->vein_count == MAX_VEINS )
	{
		snprintf( err, err_size, "%s:%d: more than %d veins", s->path, number, MAX_VEINS );
		return -1;
	}
	int32_t k = s->vein_count++;
	s->vein_line[k] = number;
	s->vein_parent[k] = parent < -1 || parent > MAX_VEINS ? MAX_VEINS : (int32_t) parent;
	s->vein_segments[k] = segments < 0 || segments > 1000000 ? -1 : (int32_t) segments;
	s->vein_bend[k] = bend;
	*block = s->vein + k;
	return 0;
}

/* An 'x y' line: a point of the open block. */
static int skeleton_point_line( skeleton_file* s, const char* word, const char* rest, int32_t number, point_list* block,
								char* err, size_t err_size )
{
	char* end;
	double x = strtod( word, &end );
	if ( *end != '\0' )
	{
		snprintf( err, err_size,
				  "%s:%d: unknown keyword '%s' (expected name, left, right, midvein, vein, or an 'x y' point)", s->path,
				  number, word );
		return -1;
	}
	double y;
	char extra[8];
	if ( sscanf( rest, " %lf %7s", &y, extra ) != 1 || !isfinite( x ) || !isfinite( y ) )
	{
		snprintf( err, err_size, "%s:%d: a point is two finite numbers 'x y'", s->path, number );
		return -1;
	}
	if ( block == NULL )
	{
		snprintf( err, err_size, "%s:%d: point outside a left, right, midvein or vein block", s->path, number );
		return -1;
	}
	if ( point_push( block, x, y, number ) != 0 )
	{
		snprintf( err, err_size, "%s: out of memory", s->path );
		return -1;
	}
	return 0;
}

/* One line of a skeleton file (comment already cut): a keyword that opens a block or names the
 * leaf, or a point of the open *block. */
static int skeleton_line( skeleton_file* s, const char* text, int32_t number, point_list** block, char* err,
						  size_t err_size )
{
	char word[64];
	int used = 0;
	if ( sscanf( text, " %63s%n", word, &used ) != 1 )
	{
		return 0;
	}
	const char* rest = text + used;
	char extra[8];
	int curve = strcmp( word, "left" ) == 0		 ? 0
				: strcmp( word, "right" ) == 0	 ? 1
				: strcmp( word, "midvein" ) == 0 ? 2
												 : -1;
	if ( curve >= 0 )
	{
		int status = 0;
		if ( sscanf( rest, " %7s", extra ) == 1 )
		{
			snprintf( err, err_size, "%s:%d: '%s' takes no value; its points follow on their own lines", s->path,
					  number, word );
			status = -1;
		}
		else if ( s->curve_line[curve] != 0 )
		{
			snprintf( err, err_size, "%s:%d: second '%s' block (the first is on line %d)", s->path, number, word,
					  s->curve_line[curve] );
			status = -1;
		}
		s->curve_line[curve] = number;
		*block = s->curve + curve;
		return status;
	}
	if ( strcmp( word, "name" ) == 0 )
	{
		char value[64];
		*block = NULL;
		if ( sscanf( rest, " %63s %7s", value, extra ) != 1 )
		{
			snprintf( err, err_size, "%s:%d: 'name' takes one word", s->path, number );
			return -1;
		}
		snprintf( s->name, sizeof( s->name ), "%s", value );
		return 0;
	}
	if ( strcmp( word, "vein" ) == 0 )
	{
		return skeleton_vein_line( s, rest, number, block, err, err_size );
	}
	return skeleton_point_line( s, word, rest, number, *block, err, err_size );
}

/* Every curve block is present with at least 2 points. */
static int skeleton_curves_complete( const skeleton_file* s, char* err, size_t err_size )
{
	static const char* const keyword[3] = { "left", "right", "midvein" };
	for ( int k = 0; k < 3; ++k )
	{
		if ( s->curve_line[k] == 0 )
		{
			snprintf( err, err_size, "%s: no '%s' block (the %s)", s->path, keyword[k], curve_names[k] );
			return -1;
		}
		if ( s->curve[k].count < 2 )
		{
			/* build_leaf measures the leaf from the midvein's first and last points */
			snprintf( err, err_size, "%s:%d: the '%s' block has %d point%s; the %s needs at least 2", s->path,
					  s->curve_line[k], keyword[k], s->curve[k].count, s->curve[k].count == 1 ? "" : "s",
					  curve_names[k] );
			return -1;
		}
	}
	return 0;
}

static int skeleton_load( const char* name, skeleton_file* s, char* err, size_t err_size )
{
	memset( s, 0, sizeof( *s ) );
	if ( skeleton_locate( name, s->path, sizeof( s->path ) ) != 0 )
	{
		snprintf( err, err_size, "cannot find skeleton '%s' (a file path, or a name in data/skeletons)", name );
		return -1;
	}
	FILE* f = fopen( s->path, "r" );
	if ( f == NULL )
	{
		snprintf( err, err_size, "%s: %s", s->path, strerror( errno ) );
		return -1;
	}
	snprintf( s->name, sizeof( s->name ), "%s", name );
	char text[1024];
	int32_t number = 0;
	point_list* block = NULL;
	int status = 0;
	while ( status == 0 && fgets( text, sizeof( text ), f ) != NULL )
	{
		++number;
		if ( strchr( text, '\n' ) == NULL && !feof( f ) )
		{
			snprintf( err, err_size, "%s:%d: line longer than %zu characters", s->path, number, sizeof( text ) - 2 );
			status = -1;
			break;
		}
		char* hash = strchr( text, '#' );
		if ( hash != NULL )
		{
			*hash = '\0';
		}
		status = skeleton_line( s, text, number, &block, err, err_size );
	}
	if ( status == 0 && ferror( f ) )
	{
		snprintf( err, err_size, "%s: %s", s->path, strerror( errno ) );
		status = -1;
	}
	fclose( f );
	if ( status == 0 )
	{
		status = skeleton_curves_complete( s, err, err_size );
	}
	if ( status != 0 )
	{
		skeleton_file_free( s );
	}
	return status;
}

/* "FILE:LINE: " for a problem the kernels found, located by curve or vein and point. */
static void skeleton_where( const skeleton_file* s, const sere_skeleton_check* check, int veins, char* out,
							size_t size )
{
	if ( s == NULL )
	{
		snprintf( out, size, "parametric leaf: " );
		return;
	}
	int32_t line = 0;
	const char* what = "";
	char label[64] = "";
	if ( veins && check->vein >= 0 && check->vein < s->vein_count )
	{
		const point_list* p = s->vein + check->vein;
		line = check->point >= 0 && check->point < p->count ? p->line[check->point] : s->vein_line[check->vein];
		snprintf( label, sizeof( label ), "vein %d", check->vein );
		what = label;
	}
	else if ( !veins && check->vein >= 0 && check->vein < 3 )
	{
		const point_list* p = s->curve + check->vein;
		line = check->point >= 0 && check->point < p->count ? p->line[check->point] : s->curve_line[check->vein];
		what = curve_names[check->vein];
	}
	if ( line > 0 )
	{
		snprintf( out, size, "%s:%d: %s: ", s->path, line, what );
	}
	else
	{
		snprintf( out, size, "%s: ", s->path );
	}
}

/* ------------------------------------------------------------------------------------------- */
/* Pictures: a shaded orthographic view drawn back to front. */

typedef struct camera
{
	double right[3], up[3], toward[3]; /* toward: from the scene to the eye */
	double scale, u0, v0;			   /* screen = ((p·right − u0) · scale, (v0 − p·up) · scale) */
	int width, height;
} camera;

static double dot3( const double* a, const double* b )
{
	return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* Fits the view to the rest plant and to its mirror image below each leaf's base, the room that
 * drooping leaves reach. */
static void camera_fit( camera* c, double azimuth, double elevation, int width, int height, const sere_plant* plant )
{
	double ca = cos( azimuth ), sa = sin( azimuth ), ce = cos( elevation ), se = sin( elevation );
	double toward[3] = { ce * ca, ce * sa, se };
	double right[3] = { -sa, ca, 0.0 };
	double up[3] = { -se * ca, -se * sa, ce };
	memcpy( c->toward, toward, sizeof( toward ) );
	memcpy( c->right, right, sizeof( right ) );
	memcpy( c->up, up, sizeof( up ) );
	double umin = INFINITY, umax = -INFINITY, vmin = INFINITY, vmax = -INFINITY;
	for ( int32_t k = 0; k < plant->leaf_count; ++k )
	{
		double root = plant->joints.z[plant->joint_first[k]];
		for ( int32_t i = plant->vertex_first[k]; i < plant->vertex_first[k + 1]; ++i )
		{
			for ( int mirror = 0; mirror < 2; ++mirror )
			{
				double z = mirror ? 2.0 * root - plant->rz[i] - 0.2 * fabs( plant->rz[i] - root ) : plant->rz[i];
				double p[3] = { plant->rx[i], plant->ry[i], z };
				double u = dot3( p, right ), v = dot3( p, up );
				umin = fmin( umin, u );
				umax = fmax( umax, u );
				vmin = fmin( vmin, v );
				vmax = fmax( vmax, v );
			}
		}
	}
	double span = fmax( ( umax - umin ) / width, ( vmax - vmin ) / ( height - 40 ) );
	c->scale = 1.0 / ( 1.1 * fmax( span, 1e-9 ) );
	c->u0 = 0.5 * ( umin + umax ) - 0.5 * width / c->scale;
	c->v0 = 0.5 * ( vmin + vmax ) + 0.5 * ( height - 30 ) / c->scale;
	c->width = width;
	c->height = height;
}

static void camera_project( const camera* c, const double p[3], double* sx, double* sy )
{
	*sx = ( dot3( p, c->right ) - c->u0 ) * c->scale;
	*sy = 30.0 + ( c->v0 - dot3( p, c->up ) ) * c->scale;
}

typedef struct depth_item
{
	float depth;
	int32_t triangle;
} depth_item;

static int depth_order( const void* a, const void* b )
{
	const depth_item* p = a;
	const depth_item* q = b;
	if ( p->depth != q->depth )
	{
		return p->depth < q->depth ? -1 : 1;
	}
	return ( p->triangle > q->triangle ) - ( p->triangle < q->triangle );
}

static cairo_status_t write_stream( void* closure, const unsigned char* data, unsigned int length )
{
	return fwrite( data, 1, length, (FILE*) closure ) == length ? CAIRO_STATUS_SUCCESS : CAIRO_STATUS_WRITE_ERROR;
}

/* The plant as it stands: stem and petioles, then leaves back to front, Lambert-shaded on both
 * sides, green turning yellow-brown with each leaf's wilting parameter. A bar at the top left
 * shows how far the run has gone, with one swatch per leaf (bottom leaf first) in its colour; no
 * text, so no font machinery. */
/* Stem from the lowest leaf base to the top, petioles from the stem to each leaf base. */
static void draw_stem( cairo_t* cr, const camera* c, const sere_plant* plant, const float* stem_top )
{
	cairo_set_source_rgb( cr, 0.35, 0.42, 0.18 );
	cairo_set_line_cap( cr, CAIRO_LINE_CAP_ROUND );
	double bottom[3] = { 0.0, 0.0, stem_top[3] }, top[3] = { 0.0, 0.0, stem_top[2] };
	double sx, sy;
	cairo_set_line_width( cr, fmax( 2.0, 0.012 * c->scale * ( stem_top[2] - stem_top[3] + 1.0 ) ) );
	camera_project( c, bottom, &sx, &sy );
	cairo_move_to( cr, sx, sy );
	camera_project( c, top, &sx, &sy );
	cairo_line_to( cr, sx, sy );
	cairo_stroke( cr );
	cairo_set_line_width( cr, 2.0 );
	for ( int32_t k = 0; k < plant->leaf_count; ++k )
	{
		int32_t root = plant->joint_first[k];
		double base[3] = { plant->joints.x[root], plant->joints.y[root], plant->joints.z[root] };
		double node[3] = { 0.0, 0.0, base[2] - 0.3 * stem_top[4] };
		camera_project( c, node, &sx, &sy );
		cairo_move_to( cr, sx, sy );
		camera_project( c, base, &sx, &sy );
		cairo_line_to( cr, sx, sy );
		cairo_stroke( cr );
	}
}

/* The triangles far to near (painter's order) by the depth of their corners' sum. */
static void sort_by_depth( const camera* c, const sere_plant* plant, depth_item* order )
{
	for ( int32_t t = 0; t < plant->triangle_count; ++t )
	{
		const int32_t* v = plant->tri + 3 * t;
		double d = 0.0;
		for ( int k = 0; k < 3; ++k )
		{
			double p[3] = { plant->x[v[k]], plant->y[v[k]], plant->z[v[k]] };
			d += dot3( p, c->toward );
		}
		order[t].depth = (float) d;
		order[t].triangle = t;
	}
	qsort( order, (size_t) plant->triangle_count, sizeof( depth_item ), depth_order );
}

/* One triangle filled in its leaf's colour (greener to browner with the leaf's wilting), shaded
 * two-sided by the light direction. */
static void draw_triangle( cairo_t* cr, const camera* c, const sere_plant* plant, int32_t t, int32_t leaf,
						   const double light[3] )
{
	const int32_t* v = plant->tri + 3 * t;
	double p[3][3];
	for ( int k = 0; k < 3; ++k )
	{
		p[k][0] = plant->x[v[k]];
		p[k][1] = plant->y[v[k]];
		p[k][2] = plant->z[v[k]];
	}
	double e1[3] = { p[1][0] - p[0][0], p[1][1] - p[0][1], p[1][2] - p[0][2] };
	double e2[3] = { p[2][0] - p[0][0], p[2][1] - p[0][1], p[2][2] - p[0][2] };
	double n[3] = { e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0] };
	double nl = sqrt( dot3( n, n ) );
	double shade = nl > 0.0 ? 0.3 + 0.7 * fabs( dot3( n, light ) ) / nl : 0.3;
	double w = 0.85 * plant->leaf_t[leaf];
	double rgb[3] = { ( 0.20 + 0.42 * w ) * shade, ( 0.52 - 0.04 * w ) * shade, ( 0.16 + 0.02 * w ) * shade };
	cairo_set_source_rgb( cr, rgb[0], rgb[1], rgb[2] );
	for ( int k = 0; k < 3; ++k )
	{
		double sx, sy;
		camera_project( c, p[k], &sx, &sy );
		if ( k == 0 )
		{
			cairo_move_to( cr, sx, sy );
		}
		else
		{
			cairo_line_to( cr, sx, sy );
		}
	}
	cairo_close_path( cr );
	/* The thin stroke in the fill colour hides the antialiasing seams between triangles. */
	cairo_fill_preserve( cr );
	cairo_stroke( cr );
}

/* The leaves, far to near, lit from above the camera and a little to its left. */
static void draw_leaves( cairo_t* cr, const camera* c, const sere_plant* plant, depth_item* order )
{
	double light[3];
	for ( int a = 0; a < 3; ++a )
	{
		light[a] = c->toward[a] + 0.8 * c->up[a] - 0.3 * c->right[a];
	}
	double ll = sqrt( dot3( light, light ) );
	for ( int a = 0; a < 3; ++a )
	{
		light[a] /= ll;
	}
	sort_by_depth( c, plant, order );
	cairo_set_line_width( cr, 0.6 );
	cairo_set_line_join( cr, CAIRO_LINE_JOIN_ROUND );
	int32_t leaf = 0;
	for ( int32_t o = 0; o < plant->triangle_count; ++o )
	{
		int32_t t = order[o].triangle;
		while ( leaf > 0 && t < plant->triangle_first[leaf] )
		{
			--leaf;
		}
		while ( t >= plant->triangle_first[leaf + 1] )
		{
			++leaf;
		}
		draw_triangle( cr, c, plant, t, leaf, light );
	}
}

/* The progress bar and one swatch per leaf in its current colour. */
static void draw_progress( cairo_t* cr, const sere_plant* plant, double progress )
{
	cairo_set_source_rgb( cr, 0.75, 0.78, 0.8 );
	cairo_rectangle( cr, 12.0, 10.0, 160.0, 6.0 );
	cairo_fill( cr );
	cairo_set_source_rgb( cr, 0.3, 0.32, 0.35 );
	cairo_rectangle( cr, 12.0, 10.0, 160.0 * progress, 6.0 );
	cairo_fill( cr );
	double swatch = fmin( 10.0, 160.0 / plant->leaf_count );
	for ( int32_t k = 0; k < plant->leaf_count; ++k )
	{
		double w = 0.85 * plant->leaf_t[k];
		cairo_set_source_rgb( cr, 0.20 + 0.42 * w, 0.52 - 0.04 * w, 0.16 + 0.02 * w );
		cairo_rectangle( cr, 12.0 + k * swatch, 20.0, 0.8 * swatch, 6.0 );
		cairo_fill( cr );
	}
}

static int render_png( const char* path, const camera* c, const sere_plant* plant, const float* stem_top,
					   depth_item* order, double progress )
{
	cairo_surface_t* surface = cairo_image_surface_create( CAIRO_FORMAT_RGB24, c->width, c->height );
	cairo_t* cr = cairo_create( surface );
	cairo_pattern_t* sky = cairo_pattern_create_linear( 0, 0, 0, c->height );
	cairo_pattern_add_color_stop_rgb( sky, 0.0, 0.86, 0.91, 0.97 );
	cairo_pattern_add_color_stop_rgb( sky, 1.0, 0.99, 0.99, 0.97 );
	cairo_set_source( cr, sky );
	cairo_paint( cr );
	cairo_pattern_destroy( sky );
	draw_stem( cr, c, plant, stem_top );
	draw_leaves( cr, c, plant, order );
	draw_progress( cr, plant, progress );
	cairo_surface_flush( surface );

	sere_atomic_file file;
	FILE* out = sere_atomic_open( &file, path );
	int result = -1;
	if ( out != NULL )
	{
		if ( cairo_surface_write_to_png_stream( surface, write_stream, out ) == CAIRO_STATUS_SUCCESS )
		{
			result = sere_atomic_commit( &file );
		}
		else
		{
			sere_atomic_abort( &file );
		}
	}
	cairo_destroy( cr );
	cairo_surface_destroy( surface );
	return result;
}

/* ------------------------------------------------------------------------------------------- */

typedef struct wilt_options
{
	const char* skeleton;
	double length, width;
	long features;
	double spacing; /* 0: length / 25 */
	long subdivide;
	double min_edge;
	sere_venation_params venation;
	sere_wilt_params wilt;
	long leaves;
	double stagger, internode, elevation;
	long frames;
	double speed; /* < 0: derived */
	const char* out;
	int ply, vtp, png;
	long every;
	double size[2], view[2];
	long threads;
	int json;
} wilt_options;

static int parse_format( const char* text, wilt_options* o )
{
	o->ply = o->vtp = o->png = 0;
	char copy[256];
	snprintf( copy, sizeof( copy ), "%s", text );
	char* save = NULL;
	int any = 0;
	for ( char* word = strtok_r( copy, ",", &save ); word != NULL; word = strtok_r( NULL, ",", &save ) )
	{
		if ( strcmp( word, "ply" ) == 0 )
		{
			o->ply = 1;
		}
		else if ( strcmp( word, "vtp" ) == 0 )
		{
			o->vtp = 1;
		}
		else if ( strcmp( word, "png" ) == 0 )
		{
			o->png = 1;
		}
		else
		{
			fprintf( stderr, "sere wilt: --format takes a comma-separated subset of ply,vtp,png, not '%s'\n", text );
			return -1;
		}
		any = 1;
	}
	if ( !any )
	{
		fprintf( stderr, "sere wilt: --format takes a comma-separated subset of ply,vtp,png, not '%s'\n", text );
		return -1;
	}
	return 0;
}

/* The leaf, venation and wilting options (see wilt_help): 1 when `a` is one of them, with *bad
 * set when its value v is not accepted. */
static int parse_leaf_value( const char* a, const char* v, wilt_options* o, int* bad )
{
	long n = 0;
	double d = 0.0;
	if ( strcmp( a, "--length" ) == 0 )
	{
		*bad = sere_parse_real( "wilt", a, v, 1e-6, 1e6, &o->length );
	}
	else if ( strcmp( a, "--width" ) == 0 )
	{
		*bad = sere_parse_real( "wilt", a, v, 1e-6, 1e6, &o->width );
	}
	else if ( strcmp( a, "--features" ) == 0 )
	{
		*bad = sere_parse_long( "wilt", a, v, 3, 10000, &o->features );
	}
	else if ( strcmp( a, "--spacing" ) == 0 )
	{
		*bad = sere_parse_real( "wilt", a, v, 1e-9, 1e6, &o->spacing );
	}
	else if ( strcmp( a, "--subdivide" ) == 0 )
	{
		*bad = sere_parse_long( "wilt", a, v, 0, 8, &o->subdivide );
	}
	else if ( strcmp( a, "--min-edge" ) == 0 )
	{
		*bad = sere_parse_real( "wilt", a, v, 0.0, 1e6, &o->min_edge );
	}
	else if ( strcmp( a, "--mid-segments" ) == 0 )
	{
		*bad = sere_parse_long( "wilt", a, v, 1, SERE_MAX_SEGMENTS, &n );
		o->venation.mid_segments = (int32_t) n;
	}
	else if ( strcmp( a, "--veins" ) == 0 )
	{
		*bad = sere_parse_long( "wilt", a, v, 0, 64, &n );
		o->venation.secondary_count = (int32_t) n;
	}
	else if ( strcmp( a, "--vein-segments" ) == 0 )
	{
		*bad = sere_parse_long( "wilt", a, v, 1, SERE_MAX_SEGMENTS, &n );
		o->venation.secondary_segments = (int32_t) n;
	}
	else if ( strcmp( a, "--vein-angle" ) == 0 )
	{
		*bad = sere_parse_real( "wilt", a, v, 1.0, 179.0, &d );
		o->venation.angle = (float) ( d * PI / 180.0 );
	}
	else if ( strcmp( a, "--mid-bend" ) == 0 )
	{
		*bad = sere_parse_real( "wilt", a, v, 0.0, 180.0, &d );
		o->venation.mid_bend = (float) ( d * PI / 180.0 );
	}
	else if ( strcmp( a, "--vein-bend" ) == 0 )
	{
		*bad = sere_parse_real( "wilt", a, v, 0.0, 180.0, &d );
		o->venation.secondary_bend = (float) ( d * PI / 180.0 );
	}
	else if ( strcmp( a, "--droop" ) == 0 )
	{
		*bad = sere_parse_real( "wilt", a, v, 0.0, 1e6, &d );
		o->wilt.droop_max = (float) d;
	}
	else if ( strcmp( a, "--min-angle" ) == 0 )
	{
		*bad = sere_parse_real( "wilt", a, v, 0.0, 180.0, &d );
		o->wilt.min_angle = (float) ( d * PI / 180.0 );
	}
	else if ( strcmp( a, "--spread" ) == 0 )
	{
		*bad = sere_parse_real( "wilt", a, v, 0.0, 0.99, &d );
		o->wilt.spread = (float) d;
	}
	else
	{
		return 0;
	}
	return 1;
}

/* The plant and run options (see wilt_help); the option is known to be one of them or one of
 * parse_leaf_value's. Returns nonzero when the value v is not accepted. */
static int parse_run_value( const char* a, const char* v, wilt_options* o )
{
	int bad = 0;
	if ( strcmp( a, "--leaves" ) == 0 )
	{
		bad = sere_parse_long( "wilt", a, v, 1, 10000, &o->leaves );
	}
	else if ( strcmp( a, "--stagger" ) == 0 )
	{
		bad = sere_parse_real( "wilt", a, v, 0.0, 100.0, &o->stagger );
	}
	else if ( strcmp( a, "--internode" ) == 0 )
	{
		bad = sere_parse_real( "wilt", a, v, 0.0, 1e6, &o->internode );
	}
	else if ( strcmp( a, "--elevation" ) == 0 )
	{
		bad = sere_parse_real( "wilt", a, v, -80.0, 80.0, &o->elevation );
	}
	else if ( strcmp( a, "--frames" ) == 0 )
	{
		bad = sere_parse_long( "wilt", a, v, 1, 1000000, &o->frames );
	}
	else if ( strcmp( a, "--speed" ) == 0 )
	{
		bad = sere_parse_real( "wilt", a, v, 0.0, 100.0, &o->speed );
	}
	else if ( strcmp( a, "--out" ) == 0 )
	{
		o->out = v;
		bad = sere_parse_dir( "wilt", a, v );
	}
	else if ( strcmp( a, "--format" ) == 0 )
	{
		bad = parse_format( v, o );
	}
	else if ( strcmp( a, "--every" ) == 0 )
	{
		bad = sere_parse_long( "wilt", a, v, 1, 1000000, &o->every );
	}
	else if ( strcmp( a, "--size" ) == 0 )
	{
		bad = parse_pair( a, v, 'x', 64, 8192, &o->size[0], &o->size[1] );
	}
	else if ( strcmp( a, "--view" ) == 0 )
	{
		bad = parse_pair( a, v, ',', -360.0, 360.0, &o->view[0], &o->view[1] );
		if ( bad == 0 && fabs( o->view[1] ) > 89.0 )
		{
			fprintf( stderr, "sere wilt: --view elevation must lie within +-89 degrees, not '%s'\n", v );
			bad = -1;
		}
	}
	else
	{
		bad = sere_parse_long( "wilt", a, v, 0, 256, &o->threads );
	}
	return bad;
}

static void wilt_defaults( wilt_options* o )
{
	memset( o, 0, sizeof( *o ) );
	o->length = 10.0;
	o->width = 6.0;
	o->features = 9;
	o->subdivide = 1;
	o->venation = sere_venation_params_default();
	o->wilt = sere_wilt_params_default();
	o->leaves = 1;
	o->stagger = 0.25;
	o->internode = -1.0;
	o->elevation = 35.0;
	o->frames = 40;
	o->speed = -1.0;
	o->ply = o->vtp = o->png = 1;
	o->every = 1;
	o->size[0] = 800;
	o->size[1] = 600;
	o->view[0] = -70.0;
	o->view[1] = 25.0;
}

/* 0 parsed (or help printed: *done = 1), 2 on a bad option. */
static int parse_options( int argc, char** argv, wilt_options* o, int* done )
{
	*done = 0;
	wilt_defaults( o );
	for ( int i = 1; i < argc; ++i )
	{
		const char* a = argv[i];
		if ( strcmp( a, "--help" ) == 0 || strcmp( a, "-h" ) == 0 )
		{
			wilt_help();
			*done = 1;
			return 0;
		}
		if ( strcmp( a, "--json" ) == 0 )
		{
			o->json = 1;
			continue;
		}
		if ( strcmp( a, "--no-pierce" ) == 0 )
		{
			o->wilt.pierce = 0;
			continue;
		}
		if ( a[0] != '-' || strcmp( a, "-" ) == 0 )
		{
			if ( o->skeleton != NULL )
			{
				fprintf( stderr, "sere wilt: one SKELETON only, got '%s' and '%s'\n", o->skeleton, a );
				return 2;
			}
			o->skeleton = a;
			continue;
		}
		const char* v = i + 1 < argc ? argv[i + 1] : NULL;
		static const char* const valued[] = {
			"--length", "--width",		   "--features",   "--spacing",	  "--subdivide", "--min-edge", "--mid-segments",
			"--veins",	"--vein-segments", "--vein-angle", "--mid-bend",  "--vein-bend", "--droop",	   "--min-angle",
			"--spread", "--leaves",		   "--stagger",	   "--internode", "--elevation", "--frames",   "--speed",
			"--out",	"--format",		   "--every",	   "--size",	  "--view",		 "--threads"
		};
		int known = 0;
		for ( size_t k = 0; k < sizeof( valued ) / sizeof( valued[0] ); ++k )
		{
			known |= strcmp( a, valued[k] ) == 0;
		}
		if ( !known )
		{
			fprintf( stderr, "sere wilt: unknown option '%s' (see sere wilt --help)\n", a );
			return 2;
		}
		if ( v == NULL )
		{
			fprintf( stderr, "sere wilt: %s needs a value\n", a );
			return 2;
		}
		++i;
		int bad = 0;
		if ( !parse_leaf_value( a, v, o, &bad ) )
		{
			bad = parse_run_value( a, v, o );
		}
		if ( bad )
		{
			return 2;
		}
	}
	return 0;
}

typedef struct wilt_run
{
	skeleton_file file;
	int have_file;
	double* parametric; /* 6 * features doubles: left, right, mid */
	sere_tri_mesh blade, mesh;
	sere_skeleton skeleton;
	sere_plant* plant;
	sere_bvh* check_bvh;
	depth_item* order;
	char** names;
	double* times;
	int32_t written;
} wilt_run;

static void wilt_run_free( wilt_run* r )
{
	if ( r->have_file )
	{
		skeleton_file_free( &r->file );
	}
	free( r->parametric );
	sere_tri_mesh_destroy( &r->blade );
	sere_tri_mesh_destroy( &r->mesh );
	sere_skeleton_destroy( &r->skeleton );
	sere_plant_destroy( r->plant );
	sere_bvh_destroy( r->check_bvh );
	free( r->order );
	for ( int32_t k = 0; k < r->written; ++k )
	{
		free( r->names[k] );
	}
	free( r->names );
	free( r->times );
}

/* Writes one frame's files; 0 on success, else -1 with a message printed. */
static int write_frame( const wilt_options* o, wilt_run* r, int64_t frame, double time, const camera* cam,
						const float* stem, float* droop, float* leaf_t )
{
	const sere_plant* p = r->plant;
	char path[4096];
	for ( int32_t k = 0; k < p->leaf_count; ++k )
	{
		for ( int32_t i = p->vertex_first[k]; i < p->vertex_first[k + 1]; ++i )
		{
			droop[i] = p->rz[i] - p->z[i];
			leaf_t[i] = p->leaf_t[k];
		}
	}
	sere_vertex_property props[4] = { { "u", p->u }, { "v", p->v }, { "droop", droop }, { "wilt_t", leaf_t } };
	if ( o->ply )
	{
		snprintf( path, sizeof( path ), "%s/frame_%04lld.ply", o->out, (long long) frame );
		if ( sere_write_ply( path, p->x, p->y, p->z, p->vertex_count, p->tri, p->triangle_count, NULL, props, 4 ) != 0 )
		{
			fprintf( stderr, "sere wilt: cannot write %s: %s\n", path, strerror( errno ) );
			return -1;
		}
	}
	if ( o->vtp )
	{
		char name[64];
		snprintf( name, sizeof( name ), "frame_%04lld.vtp", (long long) frame );
		snprintf( path, sizeof( path ), "%s/%s", o->out, name );
		if ( sere_write_vtp( path, p->x, p->y, p->z, p->vertex_count, p->tri, p->triangle_count, props, 4 ) != 0 )
		{
			fprintf( stderr, "sere wilt: cannot write %s: %s\n", path, strerror( errno ) );
			return -1;
		}
		r->names[r->written] = strdup( name );
		if ( r->names[r->written] == NULL )
		{
			fprintf( stderr, "sere wilt: out of memory\n" );
			return -1;
		}
		r->times[r->written++] = time;
		snprintf( path, sizeof( path ), "%s/wilt.pvd", o->out );
		if ( sere_write_pvd( path, (const char* const*) r->names, r->times, r->written ) != 0 )
		{
			fprintf( stderr, "sere wilt: cannot write %s: %s\n", path, strerror( errno ) );
			return -1;
		}
	}
	if ( o->png )
	{
		snprintf( path, sizeof( path ), "%s/frame_%04lld.png", o->out, (long long) frame );
		if ( render_png( path, cam, p, stem, r->order, o->frames > 1 ? (double) frame / ( o->frames - 1 ) : 1.0 ) != 0 )
		{
			fprintf( stderr, "sere wilt: cannot write %s: %s\n", path, strerror( errno ) );
			return -1;
		}
	}
	return 0;
}

/* Builds the leaf template: leaf skeleton (file or parametric), blade mesh, subdivision and
 * venation skeleton. 0 on success, else 1 with one line printed. */
static int build_leaf( const wilt_options* o, wilt_run* r, double* leaf_length )
{
	char err[4600], where[4300];
	sere_leaf_skeleton leaf;
	if ( o->skeleton != NULL )
	{
		if ( skeleton_load( o->skeleton, &r->file, err, sizeof( err ) ) != 0 )
		{
			fprintf( stderr, "sere wilt: %s\n", err );
			return 1;
		}
		r->have_file = 1;
		leaf = ( sere_leaf_skeleton ){ r->file.curve[0].count, r->file.curve[1].count, r->file.curve[2].count,
									   r->file.curve[0].xy,	   r->file.curve[1].xy,	   r->file.curve[2].xy };
	}
	else
	{
		int32_t n = (int32_t) o->features;
		r->parametric = malloc( 6 * (size_t) n * sizeof( double ) );
		if ( r->parametric == NULL ||
			 sere_leaf_skeleton_generate( o->length, o->width, n, r->parametric, r->parametric + 2 * n,
										  r->parametric + 4 * n ) != SERE_OK )
		{
			fprintf( stderr, "sere wilt: cannot make the parametric leaf (length %g, width %g, %d feature points)\n",
					 o->length, o->width, n );
			return 1;
		}
		leaf = ( sere_leaf_skeleton ){ n, n, n, r->parametric, r->parametric + 2 * n, r->parametric + 4 * n };
	}
	const skeleton_file* file = r->have_file ? &r->file : NULL;
	const double* mid = leaf.mid_xy;
	*leaf_length = hypot( mid[2 * leaf.mid_count - 2] - mid[0], mid[2 * leaf.mid_count - 1] - mid[1] );
	double spacing = o->spacing > 0.0 ? o->spacing : *leaf_length / 25.0;
	sere_skeleton_check check = { SERE_SKELETON_OK, -1, -1 };
	sere_status status = sere_blade_create( &leaf, spacing, &r->blade, &check );
	if ( status != SERE_OK )
	{
		if ( check.problem != SERE_SKELETON_OK )
		{
			skeleton_where( file, &check, 0, where, sizeof( where ) );
			fprintf( stderr, "sere wilt: %s%s\n", where, sere_skeleton_problem_text( check.problem ) );
		}
		else
		{
			fprintf( stderr, "sere wilt: %s: cannot mesh the blade: %s\n", file ? file->path : "parametric leaf",
					 sere_status_text( status ) );
		}
		return 1;
	}
	status = sere_subdivide( &r->blade, (int32_t) o->subdivide, (float) o->min_edge, &r->mesh );
	if ( status != SERE_OK )
	{
		fprintf( stderr, "sere wilt: cannot subdivide the blade %ld times: %s\n", o->subdivide,
				 sere_status_text( status ) );
		return 1;
	}
	if ( file != NULL && file->vein_count > 0 )
	{
		sere_vein_spec veins[MAX_VEINS];
		for ( int32_t k = 0; k < file->vein_count; ++k )
		{
			const point_list* p = file->vein + k;
			/* The midvein block may leave its points to the leaf skeleton's midvein. */
			int follow = k == 0 && p->count == 0;
			veins[k] = ( sere_vein_spec ){ file->vein_parent[k], file->vein_segments[k],
										   (float) ( file->vein_bend[k] * PI / 180.0 ),
										   follow ? leaf.mid_count : p->count, follow ? leaf.mid_xy : p->xy };
		}
		status = sere_skeleton_create( veins, file->vein_count, &r->skeleton, &check );
		if ( status != SERE_OK )
		{
			skeleton_where( file, &check, 1, where, sizeof( where ) );
			fprintf( stderr, "sere wilt: %s%s\n", where, sere_skeleton_problem_text( check.problem ) );
			return 1;
		}
	}
	else
	{
		status = sere_skeleton_generate( &leaf, &o->venation, &r->skeleton, &check );
		if ( status != SERE_OK )
		{
			fprintf( stderr, "sere wilt: %s: cannot generate the venation: %s\n", file ? file->path : "parametric leaf",
					 check.problem != SERE_SKELETON_OK ? sere_skeleton_problem_text( check.problem )
													   : sere_status_text( status ) );
			return 1;
		}
	}
	return 0;
}

/* What a run measured, for the summary. */
typedef struct wilt_summary
{
	int threads;
	int32_t leaves;
	double speed;
	double setup, simulate, output; /* seconds */
	sere_wilt_stats total;
	double deepest;
	int64_t intersections;
} wilt_summary;

/* The plant (Sec. 7): leaves up the stem 137.5° apart, the upper ones a little smaller, each
 * starting to wilt `stagger` after the one below. stem gets [2] its top, [3] its bottom and [4]
 * the petiole length (for the petiole nodes). */
static int build_plant( const wilt_options* o, wilt_run* r, double leaf_length, float stem[5] )
{
	int32_t leaves = (int32_t) o->leaves;
	double internode = o->internode >= 0.0 ? o->internode : 0.3 * leaf_length;
	sere_leaf_placement* placement = calloc( (size_t) leaves, sizeof( sere_leaf_placement ) );
	if ( placement == NULL )
	{
		fprintf( stderr, "sere wilt: out of memory\n" );
		return 1;
	}
	double base_height = leaves > 1 ? 0.5 * leaf_length : 0.0;
	for ( int32_t k = 0; k < leaves; ++k )
	{
		double azimuth = k * 137.5 * PI / 180.0;
		double petiole = leaves > 1 ? 0.12 * leaf_length : 0.0;
		placement[k].template_index = 0;
		placement[k].base[0] = (float) ( petiole * cos( azimuth ) );
		placement[k].base[1] = (float) ( petiole * sin( azimuth ) );
		placement[k].base[2] = (float) ( base_height + k * internode + 0.3 * petiole );
		placement[k].azimuth = (float) azimuth;
		placement[k].elevation = (float) ( o->elevation * PI / 180.0 );
		placement[k].scale = (float) ( leaves > 1 ? 1.0 - 0.35 * k / ( leaves - 1 ) : 1.0 );
		placement[k].onset = (float) ( o->stagger * k );
	}
	sere_leaf_template template = { &r->mesh, &r->skeleton };
	sere_status status = sere_plant_create( &template, 1, placement, leaves, &r->plant );
	free( placement );
	if ( status != SERE_OK )
	{
		fprintf( stderr, "sere wilt: cannot build the plant of %d leaves: %s\n", leaves, sere_status_text( status ) );
		return 1;
	}
	stem[0] = stem[1] = 0.0f;
	stem[2] = (float) ( base_height + ( leaves - 1 ) * internode + 0.05 * leaf_length );
	stem[3] = 0.0f;
	stem[4] = (float) ( leaves > 1 ? 0.12 * leaf_length : 0.0 );
	return 0;
}

/* Every frame: wilt, then write the frames asked for; sums the statistics and the times. */
static int run_frames( const wilt_options* o, wilt_run* r, const float stem[5], wilt_summary* s )
{
	sere_plant* plant = r->plant;
	int64_t pictures = ( o->frames - 1 ) / o->every + 1 + ( ( o->frames - 1 ) % o->every != 0 );
	float* droop = calloc( (size_t) plant->vertex_count, sizeof( float ) );
	float* leaf_t = calloc( (size_t) plant->vertex_count, sizeof( float ) );
	r->order = malloc( (size_t) plant->triangle_count * sizeof( depth_item ) );
	r->names = calloc( (size_t) pictures, sizeof( char* ) );
	r->times = calloc( (size_t) pictures, sizeof( double ) );
	if ( droop == NULL || leaf_t == NULL || r->order == NULL || r->names == NULL || r->times == NULL )
	{
		fprintf( stderr, "sere wilt: out of memory\n" );
		free( droop );
		free( leaf_t );
		return 1;
	}
	camera cam;
	camera_fit( &cam, o->view[0] * PI / 180.0, o->view[1] * PI / 180.0, (int) o->size[0], (int) o->size[1], plant );
	sere_progress progress;
	sere_progress_begin( &progress, "wilt", o->frames );
	int failed = 0;
	for ( int64_t frame = 0; frame < o->frames && !failed; ++frame )
	{
		double time = s->speed * (double) frame;
		double t0 = sere_now();
		sere_wilt_stats stats;
		sere_status status = sere_plant_frame( plant, (float) time, &o->wilt, &stats );
		s->simulate += sere_now() - t0;
		if ( status != SERE_OK )
		{
			fprintf( stderr, "sere wilt: frame %lld failed: %s\n", (long long) frame, sere_status_text( status ) );
			failed = 1;
			break;
		}
		s->total.pose.droop_limited += stats.pose.droop_limited;
		s->total.pose.angle_limited += stats.pose.angle_limited;
		s->total.pose.down_limited += stats.pose.down_limited;
		s->total.pierce.shortened += stats.pierce.shortened;
		s->total.pierce.pulled_back += stats.pierce.pulled_back;
		s->total.pierce.reverted += stats.pierce.reverted;
		if ( o->out != NULL && ( frame % o->every == 0 || frame == o->frames - 1 ) )
		{
			double t1 = sere_now();
			failed = write_frame( o, r, frame, time, &cam, stem, droop, leaf_t ) != 0;
			s->output += sere_now() - t1;
		}
		sere_progress_update( &progress, frame + 1 );
	}
	sere_progress_end( &progress );
	free( droop );
	free( leaf_t );
	return failed;
}

/* The final mesh checked for self-intersection with a fresh BVH (Sec. 6), and the deepest
 * joint droop. */
static void final_check( wilt_run* r, wilt_summary* s )
{
	const sere_plant* plant = r->plant;
	s->intersections = -1;
	if ( sere_bvh_create( plant->tri, plant->triangle_count, plant->vertex_count, plant->x, plant->y, plant->z,
						  &r->check_bvh ) == SERE_OK )
	{
		s->intersections = sere_mesh_count_intersections( r->check_bvh, plant->tri, plant->triangle_count, plant->x,
														  plant->y, plant->z );
	}
	s->deepest = 0.0;
	for ( int32_t j = 0; j < plant->joints.joint_count; ++j )
	{
		s->deepest = fmax( s->deepest, (double) plant->joints.z[j] - plant->frames.z[j] );
	}
}

static void print_summary( const wilt_options* o, const wilt_run* r, const wilt_summary* s )
{
	const sere_plant* plant = r->plant;
	const sere_wilt_stats* total = &s->total;
	const char* name = r->have_file ? r->file.name : "parametric";
	double per_frame = 1e3 * s->simulate / (double) o->frames;
	if ( o->json )
	{
		char name_json[6 * sizeof( r->file.name )], out_json[6 * 4096];
		sere_json_escape( name_json, sizeof( name_json ), name );
		sere_json_escape( out_json, sizeof( out_json ), o->out );
		printf( "{\"leaf\": \"%s\", \"leaves\": %d, \"blade_vertices\": %d, \"blade_triangles\": %d, "
				"\"leaf_vertices\": %d, \"leaf_triangles\": %d, \"joints_per_leaf\": %d, \"veins_per_leaf\": %d, "
				"\"vertices\": %d, \"triangles\": %d, \"frames\": %ld, \"speed\": %.6g, \"threads\": %d, \"setup_ms\": "
				"%.3f, \"frame_ms\": %.3f, \"output_ms\": %.3f, \"droop_limited\": %d, \"angle_limited\": %d, "
				"\"down_limited\": %d, \"pierce_shortened\": %d, \"pulled_back\": %d, \"reverted_frames\": %d, "
				"\"deepest_joint_droop\": %.6g, \"self_intersections\": %lld, \"out\": %s%s%s}\n",
				name_json, s->leaves, r->blade.vertex_count, r->blade.triangle_count, r->mesh.vertex_count,
				r->mesh.triangle_count, r->skeleton.joint_count, r->skeleton.vein_count, plant->vertex_count,
				plant->triangle_count, o->frames, s->speed, s->threads, 1e3 * s->setup, per_frame,
				1e3 * s->output / (double) o->frames, total->pose.droop_limited, total->pose.angle_limited,
				total->pose.down_limited, total->pierce.shortened, total->pierce.pulled_back, total->pierce.reverted,
				s->deepest, (long long) s->intersections, o->out ? "\"" : "", o->out ? out_json : "null",
				o->out ? "\"" : "" );
		return;
	}
	printf( "leaf            %s: blade %d vertices / %d triangles, after %ld subdivision(s) %d / %d\n", name,
			r->blade.vertex_count, r->blade.triangle_count, o->subdivide, r->mesh.vertex_count,
			r->mesh.triangle_count );
	printf( "venation        %d veins, %d joints per leaf\n", r->skeleton.vein_count, r->skeleton.joint_count );
	printf( "plant           %d leaves, %d vertices, %d triangles\n", s->leaves, plant->vertex_count,
			plant->triangle_count );
	printf( "run             %ld frames, t += %.4g per frame, %d threads\n", o->frames, s->speed, s->threads );
	printf( "time            setup %.1f ms, %.3f ms per frame (pose, skin%s)%s\n", 1e3 * s->setup, per_frame,
			o->wilt.pierce ? ", piercing check" : "", o->out ? ", output written separately" : "" );
	printf( "limits          droop %d, angle %d, straight down %d (joint-frames held back)\n",
			total->pose.droop_limited, total->pose.angle_limited, total->pose.down_limited );
	printf( "piercing        %s: %d moves shortened, %d vertices pulled back, %d frames undone\n",
			o->wilt.pierce ? "on" : "off", total->pierce.shortened, total->pierce.pulled_back, total->pierce.reverted );
	printf( "result          deepest joint droop %.4g, self-intersecting triangle pairs %lld\n", s->deepest,
			(long long) s->intersections );
	if ( o->out != NULL )
	{
		printf( "output          %s (%s%s%s)\n", o->out, o->ply ? "ply " : "", o->vtp ? "vtp+pvd " : "",
				o->png ? "png" : "" );
	}
}

int sere_cmd_wilt( int argc, char** argv )
{
	wilt_options o;
	int done;
	int code = parse_options( argc, argv, &o, &done );
	if ( code != 0 || done )
	{
		return code;
	}
	if ( o.out != NULL && sere_mkdirs( o.out ) != 0 )
	{
		fprintf( stderr, "sere wilt: cannot create output directory '%s': %s\n", o.out, strerror( errno ) );
		return 1;
	}
	wilt_summary s;
	memset( &s, 0, sizeof( s ) );
	s.threads = sere_topo_bind( (int) o.threads, NULL );
	s.leaves = (int32_t) o.leaves;
	double start = sere_now();
	wilt_run r;
	memset( &r, 0, sizeof( r ) );
	double leaf_length = 0.0;
	float stem[5];
	if ( build_leaf( &o, &r, &leaf_length ) != 0 || build_plant( &o, &r, leaf_length, stem ) != 0 )
	{
		wilt_run_free( &r );
		return 1;
	}
	s.setup = sere_now() - start;
	s.speed = o.speed >= 0.0 ? o.speed : ( 1.0 + o.stagger * ( s.leaves - 1 ) ) / fmax( 1.0, (double) o.frames - 1 );
	if ( run_frames( &o, &r, stem, &s ) != 0 )
	{
		wilt_run_free( &r );
		return 1;
	}
	final_check( &r, &s );
	print_summary( &o, &r, &s );
	wilt_run_free( &r );
	return 0;
}
