#include "fixture.h"
#include "mesh/measure.h"
#include "ref/measure_ref.h"

#include <criterion/criterion.h>
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#define MEASURE_PI 3.14159265358979323846

/* A grid sheet from the shared plane fixture (boundary points first, the middle row a vein when
 * asked) with what sere_shape_input needs: float positions, fresh u, v, the unique edges with
 * vein flags and the boundary flags; grid[j (nx + 1) + i] is the vertex nearest grid point
 * (i, j), which the jitter (±0.1 cell at most here) never moves by half a cell. */
typedef struct measure_sheet
{
	int32_t n, triangles, edges, nx, ny;
	double width, height;
	float *x, *y, *z, *u, *v;
	int32_t *tri, *edge_a, *edge_b, *grid;
	uint8_t *edge_vein, *boundary;
} measure_sheet;

static int compare_key( const void* a, const void* b )
{
	uint64_t u = *(const uint64_t*) a, v = *(const uint64_t*) b;
	return ( u > v ) - ( u < v );
}

static uint64_t measure_key( int32_t i, int32_t j )
{
	return i < j ? ( (uint64_t) i << 32 ) | (uint32_t) j : ( (uint64_t) j << 32 ) | (uint32_t) i;
}

static void measure_sheet_make( measure_sheet* s, int32_t nx, int32_t ny, double width, double height, double jitter,
								int vein_row, uint64_t seed )
{
	sere_test_plane plane;
	sere_test_plane_grid( &plane, nx, ny, width, height, jitter, vein_row, seed );
	s->n = plane.mesh.point_count;
	s->triangles = plane.mesh.triangle_count;
	s->nx = nx, s->ny = ny, s->width = width, s->height = height;
	float** arrays[] = { &s->x, &s->y, &s->z, &s->u, &s->v };
	for ( int k = 0; k < 5; ++k )
	{
		*arrays[k] = calloc( (size_t) s->n, sizeof( float ) );
	}
	s->boundary = calloc( (size_t) s->n, 1 );
	s->grid = malloc( sizeof( int32_t ) * (size_t) ( nx + 1 ) * (size_t) ( ny + 1 ) );
	for ( int32_t i = 0; i < s->n; ++i )
	{
		s->u[i] = (float) plane.x[i], s->v[i] = (float) plane.y[i];
		s->x[i] = s->u[i], s->y[i] = s->v[i];
		s->boundary[i] = i < plane.mesh.boundary_count;
		int32_t gi = (int32_t) lround( plane.x[i] / ( width / nx ) ),
				gj = (int32_t) lround( plane.y[i] / ( height / ny ) );
		s->grid[gj * ( nx + 1 ) + gi] = i;
	}
	s->tri = plane.tri;
	plane.tri = NULL;
	uint64_t* key = malloc( sizeof( uint64_t ) * 3 * (size_t) s->triangles );
	for ( int32_t t = 0; t < s->triangles; ++t )
	{
		for ( int k = 0; k < 3; ++k )
		{
			key[3 * t + k] = measure_key( s->tri[3 * t + k], s->tri[3 * t + ( k + 1 ) % 3] );
		}
	}
	qsort( key, 3 * (size_t) s->triangles, sizeof( uint64_t ), compare_key );
	int32_t unique = 0;
	for ( int32_t k = 0; k < 3 * s->triangles; ++k )
	{
		if ( unique == 0 || key[k] != key[unique - 1] )
		{
			key[unique++] = key[k];
		}
	}
	s->edges = unique;
	s->edge_a = malloc( sizeof( int32_t ) * (size_t) unique );
	s->edge_b = malloc( sizeof( int32_t ) * (size_t) unique );
	s->edge_vein = calloc( (size_t) unique, 1 );
	for ( int32_t e = 0; e < unique; ++e )
	{
		s->edge_a[e] = (int32_t) ( key[e] >> 32 ), s->edge_b[e] = (int32_t) ( key[e] & 0xffffffffu );
	}
	for ( int32_t k = 0; k < plane.mesh.vein_segment_count; ++k )
	{
		uint64_t want = measure_key( plane.veins[2 * k], plane.veins[2 * k + 1] );
		uint64_t* hit = bsearch( &want, key, (size_t) unique, sizeof( uint64_t ), compare_key );
		cr_assert_not_null( hit );
		s->edge_vein[hit - key] = 1;
	}
	free( key );
	sere_test_plane_free( &plane );
}

static void measure_sheet_free( measure_sheet* s )
{
	void* arrays[] = { s->x, s->y, s->z, s->u, s->v, s->tri, s->edge_a, s->edge_b, s->grid, s->edge_vein, s->boundary };
	for ( int k = 0; k < 11; ++k )
	{
		free( arrays[k] );
	}
}

static sere_shape_input measure_input( const measure_sheet* s )
{
	sere_shape_input in = sere_shape_input_default();
	in.x = s->x, in.y = s->y, in.z = s->z, in.u = s->u, in.v = s->v;
	in.vertex_count = s->n;
	in.tri = s->tri, in.triangle_count = s->triangles;
	in.edge_a = s->edge_a, in.edge_b = s->edge_b, in.edge_vein = s->edge_vein, in.edge_count = s->edges;
	in.boundary = s->boundary;
	return in;
}

/* A leaf shape holding one straight vein of order 1 from (x0, y0) to (x1, y1), for the measures
 * along and across the main veins (only the veins are read). */
typedef struct measure_vein
{
	double xy[4];
	sere_vein vein;
	sere_leaf_shape shape;
} measure_vein;

static void measure_vein_make( measure_vein* m, double x0, double y0, double x1, double y1 )
{
	memset( m, 0, sizeof( *m ) );
	m->xy[0] = x0, m->xy[1] = y0, m->xy[2] = x1, m->xy[3] = y1;
	m->vein = ( sere_vein ){ 0, 2, 1, -1 };
	m->shape.vein_count = 1, m->shape.veins = &m->vein;
	m->shape.vein_point_count = 2, m->shape.vein_xy = m->xy;
}

/* Crumpled: eight random plane waves (wavelength 0.2 to 0.5) displacing all three axes by up to
 * the amplitude, plus per-vertex noise. Amplitudes near 1 on a unit sheet fold it through
 * itself many times. */
static void measure_crumple( measure_sheet* s, double amplitude, double noise, uint64_t seed )
{
	sere_test_crumple field;
	sere_test_crumple_make( &field, amplitude, seed );
	for ( int32_t i = 0; i < s->n; ++i )
	{
		sere_test_crumple_point( &field, s->u[i], s->v[i], noise, s->x + i, s->y + i, s->z + i );
	}
}

/* A sheet of jitter 0.2 (measure_sheet_make from seed) crumpled from crumple_seed. */
static void measure_crumpled( measure_sheet* s, int32_t nx, int32_t ny, double width, double height, int vein_row,
							  uint64_t seed, double amplitude, double noise, uint64_t crumple_seed )
{
	measure_sheet_make( s, nx, ny, width, height, 0.2, vein_row, seed );
	measure_crumple( s, amplitude, noise, crumple_seed );
}

static int64_t measure_fast_count( const measure_sheet* s )
{
	int64_t count = -1;
	cr_assert_eq( sere_crossings_count_once( s->x, s->y, s->z, s->n, s->tri, s->triangles, &count, 0 ), SERE_OK );
	return count;
}

/* ---------------------------------------------------------------------------------------------
 * Crossings */

/* Strong crumples fold the sheet through itself; on top of them, degenerate input: triangles
 * collapsed onto a line (a corner on the midpoint of the other two, zero area up to rounding) or
 * onto a point pair (two corners at one position: zero normal exactly), vertices sharing the
 * position of an unrelated vertex, and triangles naming one index twice. */
Test( measure, crossings_match_brute_force_on_crumpled_sheets )
{
	int64_t total = 0;
	for ( uint64_t seed = 1; seed <= 4; ++seed )
	{
		measure_sheet s;
		measure_crumpled( &s, 24, 16, 1.0, 0.75, 0, seed, 0.9 + 0.1 * (double) seed, 0.01, 100 + seed );
		int32_t collapsed = 0, pinched = 0, shared = 0, repeated = 0;
		if ( seed >= 2 )
		{
			for ( int32_t t = 0; t < s.triangles; t += 7 )
			{
				int32_t* v = s.tri + 3 * t;
				s.x[v[2]] = 0.5f * ( s.x[v[0]] + s.x[v[1]] );
				s.y[v[2]] = 0.5f * ( s.y[v[0]] + s.y[v[1]] );
				s.z[v[2]] = 0.5f * ( s.z[v[0]] + s.z[v[1]] );
				collapsed += 1;
			}
			for ( int32_t t = 3; t < s.triangles; t += 11 )
			{
				int32_t* v = s.tri + 3 * t;
				s.x[v[1]] = s.x[v[0]], s.y[v[1]] = s.y[v[0]], s.z[v[1]] = s.z[v[0]];
				pinched += 1;
			}
			for ( int32_t i = 0; i < s.n; i += 13 )
			{
				int32_t j = (int32_t) ( ( (int64_t) i * 7919 + 17 ) % s.n );
				s.x[i] = s.x[j], s.y[i] = s.y[j], s.z[i] = s.z[j];
				shared += 1;
			}
		}
		if ( seed == 4 )
		{
			for ( int32_t t = 5; t < s.triangles; t += 29 )
			{
				s.tri[3 * t + 2] = s.tri[3 * t];
				repeated += 1;
			}
		}
		int64_t fast = measure_fast_count( &s );
		int64_t ref = sere_crossings_ref_count( s.x, s.y, s.z, s.n, s.tri, s.triangles );
		cr_assert_eq(
			fast, ref, "seed %llu (%d collapsed, %d pinched, %d shared, %d repeated): fast %lld, brute force %lld",
			(unsigned long long) seed, collapsed, pinched, shared, repeated, (long long) fast, (long long) ref );
		cr_assert_gt( ref, 0, "seed %llu: the crumple must pass the sheet through itself", (unsigned long long) seed );
		total += ref;
		measure_sheet_free( &s );
	}
	cr_log_info( "crossings over four crumpled sheets: %lld", (long long) total );
}

Test( measure, crossings_zero_on_flat_sheet )
{
	measure_sheet s;
	measure_sheet_make( &s, 30, 20, 1.5, 1.0, 0.2, 1, 3 );
	/* every volume against the plane z = 0 is exactly 0, so nothing may count */
	cr_assert_eq( measure_fast_count( &s ), 0 );
	cr_assert_eq( sere_crossings_ref_count( s.x, s.y, s.z, s.n, s.tri, s.triangles ), 0 );
	measure_sheet_free( &s );
}

/* A U-fold whose upper arm slopes down through the lower one: the two sheets meet along a line
 * across the whole width, which every row of edges of either sheet crosses once. */
Test( measure, crossings_on_sheet_folded_through_itself )
{
	measure_sheet s;
	int32_t nx = 40, ny = 12;
	measure_sheet_make( &s, nx, ny, 1.0, 0.3, 0.2, 0, 5 );
	double r = 0.05, a = 0.5 * ( 1.0 - MEASURE_PI * r ), slope = 0.4;
	for ( int32_t i = 0; i < s.n; ++i )
	{
		double u = s.u[i];
		if ( u <= a )
		{
			s.x[i] = (float) u, s.z[i] = 0.0f;
		}
		else if ( u <= a + MEASURE_PI * r )
		{
			s.x[i] = (float) ( a + r * sin( ( u - a ) / r ) );
			s.z[i] = (float) ( r - r * cos( ( u - a ) / r ) );
		}
		else
		{
			/* back over the lower arm, descending: z = 0 at a − 2r / slope, inside [0, a] */
			double back = u - a - MEASURE_PI * r;
			s.x[i] = (float) ( a - back ), s.z[i] = (float) ( 2.0 * r - slope * back );
		}
	}
	int64_t fast = measure_fast_count( &s );
	int64_t ref = sere_crossings_ref_count( s.x, s.y, s.z, s.n, s.tri, s.triangles );
	cr_assert_eq( fast, ref );
	/* The meeting line crosses each of the ny − 1 interior rows of edges of each sheet at one
	 * edge, and the jitter keeps it off vertices and edges of the other sheet. */
	cr_assert_geq( fast, 2 * ( ny - 1 ), "folded through itself: %lld crossings", (long long) fast );
	/* the same fold pulled back above the lower arm does not cross */
	for ( int32_t i = 0; i < s.n; ++i )
	{
		if ( s.u[i] > a + MEASURE_PI * r )
		{
			s.z[i] = (float) ( 2.0 * r );
		}
	}
	cr_assert_eq( measure_fast_count( &s ), 0 );
	cr_assert_eq( sere_crossings_ref_count( s.x, s.y, s.z, s.n, s.tri, s.triangles ), 0 );
	measure_sheet_free( &s );
}

/* The count is an integer sum over edges, so any thread count gives the same; the workspace is
 * reused for a second shape and must agree with a fresh one. */
Test( measure, crossings_same_for_one_and_two_threads )
{
	measure_sheet s;
	measure_crumpled( &s, 70, 70, 1.0, 1.0, 0, 8, 1.0, 0.005, 21 );
	sere_crossings* c;
	cr_assert_eq( sere_crossings_create( s.tri, s.triangles, s.n, &c ), SERE_OK );
	int saved = omp_get_max_threads();
	int64_t one = -1, two = -2;
	omp_set_num_threads( 1 );
	cr_assert_eq( sere_crossings_count( c, s.x, s.y, s.z, &one ), SERE_OK );
	omp_set_num_threads( 2 );
	cr_assert_eq( sere_crossings_count( c, s.x, s.y, s.z, &two ), SERE_OK );
	omp_set_num_threads( saved );
	cr_assert_eq( one, two );
	cr_assert_gt( one, 0 );
	measure_crumple( &s, 0.7, 0.005, 22 );
	int64_t again = -1;
	cr_assert_eq( sere_crossings_count( c, s.x, s.y, s.z, &again ), SERE_OK );
	cr_assert_eq( again, measure_fast_count( &s ) );
	cr_assert_neq( again, one, "a different crumple with the same count would hide a stale grid" );
	sere_crossings_destroy( c );
	measure_sheet_free( &s );
}

/* Three vertices flung a thousand sheet widths away make long slivers: the first grid would need
 * far more cells than the workspace holds, so the count coarsens it, and must stay exact. */
Test( measure, crossings_exact_when_the_grid_coarsens )
{
	measure_sheet s;
	measure_crumpled( &s, 20, 14, 1.0, 0.7, 0, 12, 1.0, 0.01, 31 );
	int32_t far[3] = { s.n / 3, s.n / 2, s.n - 5 };
	float where[3][3] = { { 1000.0f, 3.0f, -2.0f }, { -5.0f, 900.0f, 40.0f }, { 0.5f, -0.5f, -800.0f } };
	for ( int k = 0; k < 3; ++k )
	{
		s.x[far[k]] = where[k][0], s.y[far[k]] = where[k][1], s.z[far[k]] = where[k][2];
	}
	int64_t fast = measure_fast_count( &s );
	cr_assert_eq( fast, sere_crossings_ref_count( s.x, s.y, s.z, s.n, s.tri, s.triangles ) );
	cr_assert_gt( fast, 0 );
	measure_sheet_free( &s );
}

Test( measure, crossings_reject_bad_input )
{
	measure_sheet s;
	measure_sheet_make( &s, 6, 4, 1.0, 1.0, 0.2, 0, 1 );
	sere_crossings* c = (sere_crossings*) &s; /* must be reset to NULL on failure */
	cr_assert_eq( sere_crossings_create( s.tri, s.triangles, s.n - 1, &c ), SERE_ERR_ARGUMENT );
	cr_assert_null( c );
	cr_assert_eq( sere_crossings_create( NULL, s.triangles, s.n, &c ), SERE_ERR_ARGUMENT );
	cr_assert_eq( sere_crossings_create( s.tri, 0, s.n, &c ), SERE_ERR_ARGUMENT );
	cr_assert_eq( sere_crossings_create( s.tri, s.triangles, s.n, &c ), SERE_OK );
	int64_t count = -1;
	s.z[s.tri[4]] = NAN;
	cr_assert_eq( sere_crossings_count( c, s.x, s.y, s.z, &count ), SERE_ERR_NONFINITE );
	cr_assert_eq( count, 0 );
	s.z[s.tri[4]] = INFINITY;
	cr_assert_eq( sere_crossings_count( c, s.x, s.y, s.z, &count ), SERE_ERR_NONFINITE );
	cr_assert_eq( sere_crossings_count( c, s.x, s.y, NULL, &count ), SERE_ERR_ARGUMENT );
	sere_crossings_destroy( c );
	measure_sheet_free( &s );
}

/* The predicate alone on hand-made cases: a proper crossing; touching with an end, through a
 * corner and along the plane do not count; a degenerate triangle never counts. */
Test( measure, segment_triangle_predicate_cases )
{
	double a[3] = { 0.0, 0.0, 0.0 }, b[3] = { 1.0, 0.0, 0.0 }, c[3] = { 0.0, 1.0, 0.0 };
	double p[3] = { 0.25, 0.25, -1.0 }, q[3] = { 0.25, 0.25, 1.0 };
	cr_assert( sere_segment_crosses_triangle( p, q, a, b, c ) );
	cr_assert( sere_segment_crosses_triangle( q, p, a, b, c ) );
	cr_assert( sere_segment_crosses_triangle( p, q, a, c, b ) );
	double end[3] = { 0.25, 0.25, 0.0 };
	cr_assert_not( sere_segment_crosses_triangle( p, end, a, b, c ), "an end on the triangle only touches" );
	double corner_p[3] = { 0.0, 0.0, -1.0 }, corner_q[3] = { 0.0, 0.0, 1.0 };
	cr_assert_not( sere_segment_crosses_triangle( corner_p, corner_q, a, b, c ), "through a corner" );
	double edge_p[3] = { 0.5, 0.0, -1.0 }, edge_q[3] = { 0.5, 0.0, 1.0 };
	cr_assert_not( sere_segment_crosses_triangle( edge_p, edge_q, a, b, c ), "through an edge" );
	double in_p[3] = { -1.0, 0.25, 0.0 }, in_q[3] = { 2.0, 0.25, 0.0 };
	cr_assert_not( sere_segment_crosses_triangle( in_p, in_q, a, b, c ), "in the plane" );
	double outside_p[3] = { 2.0, 2.0, -1.0 }, outside_q[3] = { 2.0, 2.0, 1.0 };
	cr_assert_not( sere_segment_crosses_triangle( outside_p, outside_q, a, b, c ) );
	double short_q[3] = { 0.25, 0.25, -0.5 };
	cr_assert_not( sere_segment_crosses_triangle( p, short_q, a, b, c ), "stops below the plane" );
	cr_assert_not( sere_segment_crosses_triangle( p, q, a, b, b ), "two coincident corners" );
	cr_assert_not( sere_segment_crosses_triangle( p, p, a, b, c ), "a point" );
}

/* ---------------------------------------------------------------------------------------------
 * Shape measures */

Test( measure, flat_sheet )
{
	measure_sheet s;
	double w = 1.2, h = 0.8;
	measure_sheet_make( &s, 24, 16, w, h, 0.2, 1, 4 );
	sere_shape_input in = measure_input( &s );
	sere_shape m;
	cr_assert_eq( sere_shape_measure( &in, &m ), SERE_OK );
	/* The triangles tile the rectangle of the (float) boundary points: area, diameter and
	 * centroid are exact up to float rounding of the corners (relative 6e-8) and double sums. */
	cr_assert_float_eq( m.area, w * h, 1e-6 );
	cr_assert_float_eq( m.extent, sqrt( w * w + h * h ), 1e-6 );
	cr_assert_float_eq( m.centroid[0], 0.5 * w, 1e-6 );
	cr_assert_float_eq( m.centroid[1], 0.5 * h, 1e-6 );
	cr_assert_eq( m.centroid[2], 0.0 );
	/* every normal of a z = 0 triangle is exactly +z, and so is their mean */
	cr_assert_float_eq( m.mean_normal[2], 1.0, 1e-15 );
	cr_assert_eq( m.mean_normal[0], 0.0 );
	cr_assert_eq( m.mean_normal[1], 0.0 );
	cr_assert_not( m.flip );
	cr_assert_eq( m.min_z, 0.0 );
	cr_assert_eq( m.max_z, 0.0 );
	cr_assert( isnan( m.ground_gap ) );
	/* parallel normals: atan2(0, 1) = 0 exactly */
	cr_assert_eq( m.crease_vein, 0.0 );
	cr_assert_eq( m.crease_surf, 0.0 );
	cr_assert_eq( m.vein_edges, 24, "the middle row: 24 interior vein edges" );
	cr_assert_gt( m.surf_edges, 1000 );
	cr_assert_eq( m.wrinkle_sign_changes, 0 );
	/* the interior plane is z = 0 exactly and every boundary vertex lies in it */
	cr_assert_float_eq( m.margin_lift, 0.0, 1e-12 );
	/* every normal is exactly +z: every angle is 0 and so is every slope */
	cr_assert_float_eq( m.roll_tip, 0.0, 1e-12 );
	cr_assert_float_eq( m.roll_base, 0.0, 1e-12 );
	cr_assert_float_eq( m.curl_tip, 0.0, 1e-12 );
	cr_assert_float_eq( m.curl_base, 0.0, 1e-12 );
	cr_assert( isnan( m.crease_main ) && isnan( m.vein_roll_tip ), "no veins given" );
	cr_assert_eq( m.midvein_curvature, 0.0, "no midvein given" );
	in.ground = -0.25;
	cr_assert_eq( sere_shape_measure( &in, &m ), SERE_OK );
	cr_assert_float_eq( m.ground_gap, 0.25, 1e-15 );
	measure_sheet_free( &s );
}

/* Rolled across its width around an axis along v through the midvein: radius R, total angle
 * phi = width / R, the z-up side inside. A regular grid, so each cross-section row is a polygon
 * of nx equal chords on the circle and every quad stays planar: all the bending sits on the
 * nx − 1 interior columns of edges along v, each turned by phi / nx. */
Test( measure, rolled_cylinder )
{
	measure_sheet s;
	int32_t nx = 16, ny = 20;
	double w = 1.0, h = 2.0, phi = 2.0, radius = w / phi;
	measure_sheet_make( &s, nx, ny, w, h, 0.0, 0, 1 );
	for ( int32_t i = 0; i < s.n; ++i )
	{
		double angle = ( s.u[i] - 0.5 * w ) / radius;
		s.x[i] = (float) ( 0.5 * w + radius * sin( angle ) );
		s.z[i] = (float) ( radius * ( 1.0 - cos( angle ) ) );
	}
	int32_t* midvein = malloc( sizeof( int32_t ) * (size_t) ( ny + 1 ) );
	for ( int32_t j = 0; j <= ny; ++j )
	{
		midvein[j] = s.grid[j * ( nx + 1 ) + nx / 2];
	}
	measure_vein vein;
	measure_vein_make( &vein, 0.5 * w, 0.0, 0.5 * w, h );
	sere_shape_input in = measure_input( &s );
	in.midvein = midvein, in.midvein_count = ny + 1;
	in.veins = &vein.shape;
	sere_shape m;
	cr_assert_eq( sere_shape_measure( &in, &m ), SERE_OK );
	/* Column c of cells is a flat strip whose normal sits at the angle of its chord's middle, so
	 * θ is a step function of the column's middle m_c; the two triangles of a cell have their
	 * centroids at m_c ∓ δ, δ = w / (6 nx), which adds δ² to the variance of the lateral
	 * coordinate: the fitted slope is (1/R) var(m) / (var(m) + δ²) = (1/R) 3(nx² − 1) / (3 nx² − 2),
	 * and times the width w the roll is phi times that ratio (0.998695 for nx = 16). Float
	 * positions tilt normals by ~1e-7 rad: 1e-5, while the continuous arc (phi itself) would be
	 * off by 2.6e-3. Sections across the vein along the middle column see the same columns. */
	double fit = 3.0 * ( nx * nx - 1.0 ) / ( 3.0 * nx * nx - 2.0 );
	cr_assert_float_eq( m.roll_tip, phi * fit, 1e-5, "%.9g", m.roll_tip );
	cr_assert_float_eq( m.roll_base, phi * fit, 1e-5, "%.9g", m.roll_base );
	cr_assert_float_eq( m.vein_roll_tip, phi * fit, 1e-5, "%.9g", m.vein_roll_tip );
	cr_assert_float_eq( m.vein_roll_base, phi * fit, 1e-5, "%.9g", m.vein_roll_base );
	/* +v maps to +y everywhere: no curl along the length */
	cr_assert_float_eq( m.curl_tip, 0.0, 1e-6 );
	cr_assert_float_eq( m.curl_base, 0.0, 1e-6 );
	/* rolled the other way (the margins towards the lower face): the same angle, negative */
	for ( int32_t i = 0; i < s.n; ++i )
	{
		s.z[i] = -s.z[i];
	}
	sere_shape down;
	cr_assert_eq( sere_shape_measure( &in, &down ), SERE_OK );
	cr_assert_float_eq( down.roll_tip, -phi * fit, 1e-5, "%.9g", down.roll_tip );
	for ( int32_t i = 0; i < s.n; ++i )
	{
		s.z[i] = -s.z[i];
	}
	double ratio = sin( 0.5 * phi ) / ( nx * sin( 0.5 * phi / nx ) );
	/* the mean of nx unit normals spread evenly over phi: this ratio along +z */
	cr_assert_float_eq( m.mean_normal[2], ratio, 1e-6 );
	cr_assert_float_eq( m.mean_normal[0], 0.0, 1e-6 );
	cr_assert_not( m.flip );
	double bent = phi / nx;
	double interior = ( nx - 1 ) * ny + nx * ( ny - 1 ) + nx * ny;
	/* Rounding of positions (3e-8 at radius 0.5) over cells of 1/16 tilts a normal by up to
	 * ~5e-7 rad, so a dihedral is within ~1e-6 of phi / nx: 1e-5. */
	cr_assert_float_eq( m.crease_surf, ( nx - 1 ) * ny * bent / interior, 1e-5 );
	cr_assert_eq( m.wrinkle_sign_changes, 0, "one sign of bending everywhere" );
	cr_assert_float_eq( m.extent, hypot( 2.0 * radius * sin( 0.5 * phi ), h ), 1e-6 );
	cr_assert_float_eq( m.area, h * nx * 2.0 * radius * sin( 0.5 * bent ), 1e-5 );
	/* the midvein lies on the cylinder's axis line x = w / 2, z = 0 exactly: straight */
	cr_assert_eq( m.midvein_curvature, 0.0 );
	/* the sign: rolled towards +z, the side the normals point to, so every bent edge is +phi/nx */
	double* dihedral = malloc( sizeof( double ) * (size_t) s.edges );
	cr_assert_eq( sere_shape_dihedrals( &in, dihedral ), SERE_OK );
	int32_t bent_edges = 0;
	for ( int32_t e = 0; e < s.edges; ++e )
	{
		if ( fabs( dihedral[e] ) > 1e-3 )
		{
			cr_assert_float_eq( dihedral[e], bent, 1e-5, "edge %d: %g", e, dihedral[e] );
			bent_edges += 1;
		}
	}
	cr_assert_eq( bent_edges, ( nx - 1 ) * ny );
	free( dihedral );
	free( midvein );
	measure_sheet_free( &s );
}

/* Curled along its length around an axis along u: a line along v becomes an arc of radius R,
 * every cross-section row stays straight. The "midvein" is the outline's left side u = 0, which
 * the fixture does not jitter (a jittered column would wander off the circle's plane by the
 * jitter). Turned to an arbitrary orientation as well, since the circle fit must first find the
 * plane of the midvein. */
Test( measure, curled_lengthwise )
{
	measure_sheet s;
	int32_t nx = 12, ny = 24;
	double w = 1.0, h = 2.0, radius = 1.6;
	measure_sheet_make( &s, nx, ny, w, h, 0.2, 1, 6 );
	int32_t* midvein = malloc( sizeof( int32_t ) * (size_t) ( ny + 1 ) );
	for ( int32_t j = 0; j <= ny; ++j )
	{
		midvein[j] = s.grid[j * ( nx + 1 )];
	}
	/* a rotation by 0.7 rad about the unit axis (2, −1, 2) / 3 (Rodrigues) */
	double k[3] = { 2.0 / 3.0, -1.0 / 3.0, 2.0 / 3.0 }, c = cos( 0.7 ), sn = sin( 0.7 );
	for ( int turned = 0; turned < 2; ++turned )
	{
		for ( int32_t i = 0; i < s.n; ++i )
		{
			double p[3] = { s.u[i], radius * sin( s.v[i] / radius ), radius * ( 1.0 - cos( s.v[i] / radius ) ) };
			if ( turned )
			{
				double kp = k[0] * p[0] + k[1] * p[1] + k[2] * p[2];
				double kxp[3] = { k[1] * p[2] - k[2] * p[1], k[2] * p[0] - k[0] * p[2], k[0] * p[1] - k[1] * p[0] };
				for ( int a = 0; a < 3; ++a )
				{
					p[a] = p[a] * c + kxp[a] * sn + k[a] * kp * ( 1.0 - c );
				}
			}
			s.x[i] = (float) p[0], s.y[i] = (float) p[1], s.z[i] = (float) p[2];
		}
		sere_shape_input in = measure_input( &s );
		in.midvein = midvein, in.midvein_count = ny + 1;
		sere_shape m;
		cr_assert_eq( sere_shape_measure( &in, &m ), SERE_OK );
		/* Points on the circle up to float rounding (~1e-7 of a sagitta of h² / 8R = 0.31): the
		 * fit is within 1e-6 relative; 1e-5 relative leaves margin. */
		cr_assert_float_eq( m.midvein_curvature, 1.0 / radius, 1e-5 / radius, "turned %d: %g", turned,
							m.midvein_curvature );
		/* The curl turns the surface about the u axis only, so nothing turns across a section. A
		 * jittered triangle inscribed in the cylinder tilts its normal about v by up to its
		 * sagitta over its width, (Δv)² / 8R / Δu ≈ 1e-2, but those tilts do not grow from one
		 * margin to the other, so the fitted turning stays near 0 (1e-4 measured): 1e-3. */
		cr_assert_float_eq( m.roll_tip, 0.0, 1e-3, "%g", m.roll_tip );
		cr_assert_float_eq( m.roll_base, 0.0, 1e-3, "%g", m.roll_base );
		/* The axis turns by Δv / R between bands 0.38 h apart: 0.475 rad. Each band's direction is
		 * the mean over triangles whose centroids lie within ±0.06 of its centre; their rows are
		 * not symmetric about it, which moves its mean v by up to ~0.02 (a third of a cell plus
		 * the jitter), 0.0125 rad at R = 1.6, per band: 0.03. */
		cr_assert_float_eq( m.curl_tip, 0.38 * h / radius, 0.03, "%g", m.curl_tip );
		cr_assert_float_eq( m.curl_base, 0.38 * h / radius, 0.03, "%g", m.curl_base );
		cr_assert_eq( m.wrinkle_sign_changes, 0 );
		/* Each row of cells (length dv = h / ny along the curl) becomes a flat strip across the
		 * chord of its arc, shorter by sin(x) / x with x = dv / 2R; the jitter (±0.1 cell)
		 * changes that by ~1e-6 of the area: 1e-5. */
		double x = 0.5 * h / ny / radius;
		cr_assert_float_eq( m.area, w * h * sin( x ) / x, 1e-5, "turned %d: area %.9g", turned, m.area );
	}
	free( midvein );
	measure_sheet_free( &s );
}

/* One sharp fold along the vein row, the far half turned up by alpha about the row: the vein
 * edges carry the whole fold, every other edge lies within one flat half. */
Test( measure, fold_along_vein )
{
	measure_sheet s;
	int32_t nx = 20, ny = 16;
	double w = 1.0, h = 0.8, mid = 0.5 * h, alpha = 0.6;
	measure_sheet_make( &s, nx, ny, w, h, 0.2, 1, 7 );
	for ( int sense = 1; sense >= -1; sense -= 2 )
	{
		for ( int32_t i = 0; i < s.n; ++i )
		{
			double d = s.v[i] - mid;
			s.y[i] = d > 0.0 ? (float) ( mid + d * cos( alpha ) ) : s.v[i];
			s.z[i] = d > 0.0 ? (float) ( sense * d * sin( alpha ) ) : 0.0f;
		}
		measure_vein vein;
		measure_vein_make( &vein, 0.0, mid, w, mid );
		sere_shape_input in = measure_input( &s );
		in.ground = 0.0;
		in.veins = &vein.shape;
		sere_shape m;
		cr_assert_eq( sere_shape_measure( &in, &m ), SERE_OK );
		/* Rounding of float positions over cells of 0.05 tilts a normal by ~1e-6 rad: 1e-5. */
		cr_assert_eq( m.vein_edges, nx );
		cr_assert_float_eq( m.crease_vein, alpha, 1e-5 );
		cr_assert_float_eq( m.crease_surf, 0.0, 1e-5 );
		/* Along the main vein: the interior edges whose fresh midpoint lies within one mean edge
		 * length of the line v = mid (the vein spans the sheet, so that is |Δv|); the nx vein
		 * edges carry alpha, the others none. Every edge two lengths away or more is flat. */
		double spacing = 0.0;
		for ( int32_t e = 0; e < s.edges; ++e )
		{
			spacing += hypot( s.u[s.edge_b[e]] - s.u[s.edge_a[e]], s.v[s.edge_b[e]] - s.v[s.edge_a[e]] );
		}
		spacing /= s.edges;
		int32_t near = 0;
		for ( int32_t e = 0; e < s.edges; ++e )
		{
			int sides = 0; /* triangles on the edge: 2 inside the sheet, 1 on its outline */
			for ( int32_t t = 0; t < s.triangles; ++t )
			{
				for ( int k = 0; k < 3; ++k )
				{
					sides += measure_key( s.tri[3 * t + k], s.tri[3 * t + ( k + 1 ) % 3] ) ==
							 measure_key( s.edge_a[e], s.edge_b[e] );
				}
			}
			double dv = 0.5 * ( (double) s.v[s.edge_a[e]] + s.v[s.edge_b[e]] ) - mid;
			near += sides == 2 && fabs( dv ) <= spacing;
		}
		cr_assert_float_eq( m.crease_main, alpha * nx / near, 1e-5, "%g over %d edges", m.crease_main, near );
		cr_assert_float_eq( m.crease_blade, 0.0, 1e-5 );
		cr_assert_eq( m.wrinkle_sign_changes, 0 );
		cr_assert_float_eq( m.ground_gap, sense > 0 ? 0.0 : -mid * sin( alpha ), 1e-6 );
		double* dihedral = malloc( sizeof( double ) * (size_t) s.edges );
		cr_assert_eq( sere_shape_dihedrals( &in, dihedral ), SERE_OK );
		for ( int32_t e = 0; e < s.edges; ++e )
		{
			if ( s.edge_vein[e] )
			{
				/* folded up towards the normals: a valley, positive */
				cr_assert_float_eq( dihedral[e], sense * alpha, 1e-5, "vein edge %d: %g", e, dihedral[e] );
			}
		}
		free( dihedral );
	}
	measure_sheet_free( &s );
}

/* An egg-crate z = A sin(k u) sin(k v) of wavelength four cells: saddles everywhere, so many
 * triangles hold a ridge edge and a valley edge; the same sheet cupped into a bowl holds none. */
Test( measure, wrinkled_sheet_changes_sign )
{
	measure_sheet s;
	int32_t n = 24;
	measure_sheet_make( &s, n, n, 1.0, 1.0, 0.2, 0, 9 );
	double k = 2.0 * MEASURE_PI * n / 4.0, amplitude = 0.02;
	for ( int32_t i = 0; i < s.n; ++i )
	{
		s.z[i] = (float) ( amplitude * sin( k * s.u[i] ) * sin( k * s.v[i] ) );
	}
	sere_shape_input in = measure_input( &s );
	sere_shape m;
	cr_assert_eq( sere_shape_measure( &in, &m ), SERE_OK );
	cr_log_info( "egg-crate: %lld sign changes over %d triangles, crease %g", (long long) m.wrinkle_sign_changes,
				 s.triangles, m.crease_surf );
	cr_assert_gt( m.wrinkle_sign_changes, s.triangles / 10 );
	cr_assert_gt( m.crease_surf, 0.1 );
	for ( int32_t i = 0; i < s.n; ++i )
	{
		double du = s.u[i] - 0.5, dv = s.v[i] - 0.5;
		s.z[i] = (float) ( 0.8 * ( du * du + dv * dv ) );
	}
	cr_assert_eq( sere_shape_measure( &in, &m ), SERE_OK );
	cr_assert_eq( m.wrinkle_sign_changes, 0 );
	measure_sheet_free( &s );
}

/* The border bent up (then down) over its outer two cells, z = ±(b − d)² / b at distance d < b
 * from the outline: the fitted interior plane stays horizontal by symmetry, lifted by the mean
 * interior height, so the margin sits ±b minus that above it. */
Test( measure, margin_lift_sign )
{
	measure_sheet s;
	int32_t n = 20;
	double w = 1.0, b = 2.0 / n;
	measure_sheet_make( &s, n, n, w, w, 0.2, 0, 10 );
	sere_shape_input in = measure_input( &s );
	sere_shape m;
	double up_lift = 0.0;
	for ( int sense = 1; sense >= -1; sense -= 2 )
	{
		double interior_sum = 0.0;
		int32_t interior = 0;
		for ( int32_t i = 0; i < s.n; ++i )
		{
			double d = fmin( fmin( s.u[i], w - s.u[i] ), fmin( s.v[i], w - s.v[i] ) );
			s.z[i] = d < b ? (float) ( sense * ( b - d ) * ( b - d ) / b ) : 0.0f;
			if ( !s.boundary[i] )
			{
				interior_sum += s.z[i], interior += 1;
			}
		}
		cr_assert_eq( sere_shape_measure( &in, &m ), SERE_OK );
		/* jitter makes the lifted ring slightly uneven, which can tilt the fitted plane a
		 * little: 5% of b */
		double expected = sense * b - interior_sum / interior;
		cr_assert_float_eq( m.margin_lift, expected, 0.05 * b, "sense %d: %g against %g", sense, m.margin_lift,
							expected );
		cr_assert( sense > 0 ? m.margin_lift > 0.0 : m.margin_lift < 0.0 );
		cr_assert_not( m.flip );
		if ( sense > 0 )
		{
			up_lift = m.margin_lift;
		}
	}
	/* The up-bent leaf turned over (half a turn about the v axis): its mean normal now points
	 * down, and the lift, measured along it, is unchanged (a rigid motion; rounding 1e-9). */
	for ( int32_t i = 0; i < s.n; ++i )
	{
		double d = fmin( fmin( s.u[i], w - s.u[i] ), fmin( s.v[i], w - s.v[i] ) );
		s.x[i] = (float) ( w - s.u[i] );
		s.z[i] = d < b ? (float) ( -( b - d ) * ( b - d ) / b ) : 0.0f;
	}
	cr_assert_eq( sere_shape_measure( &in, &m ), SERE_OK );
	cr_assert( m.flip );
	cr_assert_float_eq( m.margin_lift, up_lift, 1e-9 );
	measure_sheet_free( &s );
}

/* The dihedrals and area against the reference twin on crumpled sheets, which bend every edge by
 * a different angle and sign: the two routes differ by double rounding only, 1e-9 rad. */
Test( measure, dihedrals_and_area_match_reference )
{
	for ( uint64_t seed = 1; seed <= 3; ++seed )
	{
		measure_sheet s;
		measure_crumpled( &s, 20, 16, 1.0, 0.8, 1, seed, 0.3, 0.01, 40 + seed );
		sere_shape_input in = measure_input( &s );
		double* fast = malloc( sizeof( double ) * (size_t) s.edges );
		double* ref = malloc( sizeof( double ) * (size_t) s.edges );
		double ref_area;
		cr_assert_eq( sere_shape_dihedrals( &in, fast ), SERE_OK );
		sere_shape_ref_dihedrals( s.x, s.y, s.z, s.tri, s.triangles, s.edge_a, s.edge_b, s.edges, ref, &ref_area );
		int32_t large = 0;
		for ( int32_t e = 0; e < s.edges; ++e )
		{
			/* angles near ±π may come out with either sign: compare around the circle */
			double diff = remainder( fast[e] - ref[e], 2.0 * MEASURE_PI );
			cr_assert_float_eq( diff, 0.0, 1e-9, "seed %llu edge %d: %.17g against %.17g", (unsigned long long) seed, e,
								fast[e], ref[e] );
			large += fabs( ref[e] ) > 0.05;
		}
		cr_assert_gt( large, s.edges / 4, "the crumple must bend many edges" );
		sere_shape m;
		cr_assert_eq( sere_shape_measure( &in, &m ), SERE_OK );
		cr_assert_float_eq( m.area, ref_area, 1e-12 * ref_area );
		cr_assert_gt( m.wrinkle_sign_changes, 0, "a crumple bends both ways" );
		free( fast );
		free( ref );
		measure_sheet_free( &s );
	}
}

/* Sequential sums and an exact max: the same measures for one and two threads. */
Test( measure, shape_same_for_one_and_two_threads )
{
	measure_sheet s;
	measure_crumpled( &s, 40, 30, 1.0, 0.75, 1, 13, 0.6, 0.01, 51 );
	sere_shape_input in = measure_input( &s );
	sere_shape one, two;
	int saved = omp_get_max_threads();
	omp_set_num_threads( 1 );
	cr_assert_eq( sere_shape_measure( &in, &one ), SERE_OK );
	omp_set_num_threads( 2 );
	cr_assert_eq( sere_shape_measure( &in, &two ), SERE_OK );
	omp_set_num_threads( saved );
	cr_assert_eq( one.extent, two.extent );
	cr_assert_eq( one.area, two.area );
	cr_assert_eq( one.crease_surf, two.crease_surf );
	cr_assert_eq( one.margin_lift, two.margin_lift );
	cr_assert_eq( one.wrinkle_sign_changes, two.wrinkle_sign_changes );
	/* and the diameter is the brute-force max */
	double best = 0.0;
	for ( int32_t i = 0; i < s.n; ++i )
	{
		for ( int32_t j = 0; j < i; ++j )
		{
			double d = hypot( hypot( (double) s.x[i] - s.x[j], (double) s.y[i] - s.y[j] ), (double) s.z[i] - s.z[j] );
			best = fmax( best, d );
		}
	}
	cr_assert_float_eq( one.extent, best, 1e-12, "sqrt of a sum against nested hypot: rounding only" );
	measure_sheet_free( &s );
}

/* pose_only measures the pose and the rolls with the very arithmetic of the full measure (the
 * same bits) and marks every other measure unmeasured, on a crumpled sheet with a vein along its
 * middle and that vein as its midvein, where the full measure gives every one of them a value. */
Test( measure, pose_only_is_the_full_measure_s_pose_and_rolls )
{
	measure_sheet s;
	const int32_t nx = 40, ny = 30;
	const double w = 1.0, h = 0.75;
	measure_crumpled( &s, nx, ny, w, h, 1, 13, 0.6, 0.01, 53 );
	int32_t midvein[31];
	for ( int32_t j = 0; j <= ny; ++j )
	{
		midvein[j] = s.grid[j * ( nx + 1 ) + nx / 2];
	}
	measure_vein vein;
	measure_vein_make( &vein, 0.5 * w, 0.0, 0.5 * w, h );
	sere_shape_input in = measure_input( &s );
	in.ground = -0.5;
	in.midvein = midvein, in.midvein_count = ny + 1;
	in.veins = &vein.shape;
	sere_shape full, pose;
	cr_assert_eq( sere_shape_measure( &in, &full ), SERE_OK );
	in.pose_only = true;
	cr_assert_eq( sere_shape_measure( &in, &pose ), SERE_OK );
	cr_assert_eq( pose.area, full.area );
	cr_assert_eq( pose.extent, full.extent, "pose_only leaves the extent to skip_extent" );
	for ( int k = 0; k < 3; ++k )
	{
		cr_assert_eq( pose.centroid[k], full.centroid[k] );
		cr_assert_eq( pose.mean_normal[k], full.mean_normal[k] );
	}
	cr_assert_eq( pose.flip, full.flip );
	cr_assert_eq( pose.min_z, full.min_z );
	cr_assert_eq( pose.max_z, full.max_z );
	cr_assert_eq( pose.ground_gap, full.ground_gap );
	cr_assert( isfinite( full.roll_tip ) && isfinite( full.roll_base ), "the sheet must have rolls to compare" );
	cr_assert_eq( pose.roll_tip, full.roll_tip );
	cr_assert_eq( pose.roll_base, full.roll_base );
	const double full_skipped[] = { full.crease_vein,	 full.crease_surf,		full.margin_lift,  full.curl_tip,
									full.curl_base,		 full.crease_main,		full.crease_blade, full.vein_roll_tip,
									full.vein_roll_base, full.midvein_curvature };
	const double pose_skipped[] = { pose.crease_vein,	 pose.crease_surf,		pose.margin_lift,  pose.curl_tip,
									pose.curl_base,		 pose.crease_main,		pose.crease_blade, pose.vein_roll_tip,
									pose.vein_roll_base, pose.midvein_curvature };
	for ( int k = 0; k < 10; ++k )
	{
		cr_assert( isfinite( full_skipped[k] ), "measure %d: the full measure must give it a value to skip", k );
		cr_assert( isnan( pose_skipped[k] ), "measure %d: pose_only skips it, yet it reads as a number", k );
	}
	cr_assert( full.wrinkle_sign_changes > 0 && full.vein_edges > 0 && full.surf_edges > 0,
			   "the full measure of a crumpled sheet counts wrinkles and edges" );
	cr_assert( pose.wrinkle_sign_changes == -1 && pose.vein_edges == -1 && pose.surf_edges == -1,
			   "a count pose_only skips reads as a count" );
	measure_sheet_free( &s );
}

Test( measure, shape_rejects_bad_input )
{
	measure_sheet s;
	measure_sheet_make( &s, 6, 4, 1.0, 1.0, 0.2, 0, 2 );
	sere_shape_input in = measure_input( &s );
	sere_shape m;
	cr_assert_eq( sere_shape_measure( &in, &m ), SERE_OK );
	cr_assert_eq( sere_shape_measure( NULL, &m ), SERE_ERR_ARGUMENT );
	cr_assert_eq( sere_shape_measure( &in, NULL ), SERE_ERR_ARGUMENT );
	in.edge_count -= 1; /* a triangle edge missing */
	cr_assert_eq( sere_shape_measure( &in, &m ), SERE_ERR_ARGUMENT );
	in.edge_count += 1;
	in.ground = NAN;
	cr_assert_eq( sere_shape_measure( &in, &m ), SERE_ERR_ARGUMENT );
	in.ground = -INFINITY;
	in.band = 0.0;
	cr_assert_eq( sere_shape_measure( &in, &m ), SERE_ERR_ARGUMENT );
	in.band = 0.05;
	measure_vein vein;
	measure_vein_make( &vein, 0.0, 0.5, 1.0, 0.5 );
	in.veins = &vein.shape;
	in.main_order = 0; /* no vein is of order 0 or lower: a mistake, not an empty choice */
	cr_assert_eq( sere_shape_measure( &in, &m ), SERE_ERR_ARGUMENT );
	in.main_order = 2;
	cr_assert_eq( sere_shape_measure( &in, &m ), SERE_OK );
	in.veins = NULL;
	/* one triangle turned over: its edges run the same way as its neighbours' */
	int32_t swap = s.tri[1];
	s.tri[1] = s.tri[2], s.tri[2] = swap;
	cr_assert_eq( sere_shape_measure( &in, &m ), SERE_ERR_GEOMETRY );
	s.tri[2] = s.tri[1], s.tri[1] = swap;
	s.y[3] = NAN;
	cr_assert_eq( sere_shape_measure( &in, &m ), SERE_ERR_NONFINITE );
	s.y[3] = s.v[3];
	cr_assert_eq( sere_shape_measure( &in, &m ), SERE_OK );
	double roll;
	in.band = 0.1; /* the rows of triangles nearest the middle have centroids 0.083 from it */
	cr_assert_eq( sere_shape_roll( &in, 0.5, &roll ), SERE_OK );
	cr_assert_float_eq( roll, 0.0, 1e-12 );
	in.band = 1e-6; /* no row this close to the middle: nothing to measure */
	cr_assert_eq( sere_shape_roll( &in, 0.4, &roll ), SERE_OK );
	cr_assert( isnan( roll ) );
	measure_sheet_free( &s );
}
