/* The improved mass-spring model of seed 002 (Sec. 4): masses from the mask by Tang Eq. 3, the
 * strain limit of Tang Eq. 2 holding after every step, dark (light) regions deforming more than
 * bright (heavy) ones under the same forces (Fig. 3–6), agreement with the scalar reference twin,
 * 1 and 2 threads bitwise equal, and bad input refused. */
#include "ref/massspring_ref.h"
#include "season/massspring.h"

#include <criterion/criterion.h>
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

/* A square sheet [-0.5, 0.5]² of n × n cells, each cut into two triangles along a diagonal that
 * flips at the middle column, so the mesh is mirror-symmetric about x = 0. z = cup · r² gives
 * the slight cup a real leaf has (see massspring.h: it picks the side the blade curls to). */
typedef struct sheet
{
	int32_t n, vertex_count, triangle_count;
	float *x, *y, *z, *vx, *vy, *vz, *inv_m;
	int32_t* tri;
} sheet;

static sheet sheet_make( int32_t n, float cup )
{
	sheet s = { 0 };
	s.n = n;
	s.vertex_count = ( n + 1 ) * ( n + 1 );
	s.triangle_count = 2 * n * n;
	size_t bytes = (size_t) s.vertex_count * sizeof( float );
	s.x = malloc( bytes );
	s.y = malloc( bytes );
	s.z = malloc( bytes );
	s.vx = calloc( 1, bytes );
	s.vy = calloc( 1, bytes );
	s.vz = calloc( 1, bytes );
	s.inv_m = malloc( bytes );
	s.tri = malloc( 3 * (size_t) s.triangle_count * sizeof( int32_t ) );
	cr_assert( s.x && s.y && s.z && s.vx && s.vy && s.vz && s.inv_m && s.tri );
	for ( int32_t j = 0; j <= n; ++j )
	{
		for ( int32_t i = 0; i <= n; ++i )
		{
			int32_t v = j * ( n + 1 ) + i;
			s.x[v] = (float) i / (float) n - 0.5f;
			s.y[v] = (float) j / (float) n - 0.5f;
			s.z[v] = cup * ( s.x[v] * s.x[v] + s.y[v] * s.y[v] );
			s.inv_m[v] = 1.0f;
		}
	}
	int32_t t = 0;
	for ( int32_t j = 0; j < n; ++j )
	{
		for ( int32_t i = 0; i < n; ++i )
		{
			int32_t a = j * ( n + 1 ) + i, b = a + 1, c = a + n + 1, d = c + 1;
			int32_t* q = s.tri + 3 * t;
			if ( 2 * i < n )
			{
				q[0] = a, q[1] = b, q[2] = d, q[3] = a, q[4] = d, q[5] = c;
			}
			else
			{
				q[0] = a, q[1] = b, q[2] = c, q[3] = b, q[4] = d, q[5] = c;
			}
			t += 2;
		}
	}
	return s;
}

static void sheet_free( sheet* s )
{
	free( s->x );
	free( s->y );
	free( s->z );
	free( s->vx );
	free( s->vy );
	free( s->vz );
	free( s->inv_m );
	free( s->tri );
}

static sere_massspring_particles sheet_particles( sheet* s )
{
	return ( sere_massspring_particles ){ s->vertex_count, s->x, s->y, s->z, s->vx, s->vy, s->vz, s->inv_m };
}

static sere_massspring* sheet_springs( const sheet* s )
{
	sere_massspring* ms = NULL;
	cr_assert_eq( sere_massspring_create( s->x, s->y, s->z, s->vertex_count, s->tri, s->triangle_count, &ms ),
				  SERE_OK );
	return ms;
}

/* max | |x_b − x_a| / L − 1 | over the structural springs, computed here in double. */
static double max_strain( const sere_massspring* ms, const sheet* s, float shrink )
{
	sere_massspring_topology t = sere_massspring_get_topology( ms );
	double worst = 0.0;
	for ( int32_t k = 0; k < t.structural_count; ++k )
	{
		double dx = (double) s->x[t.b[k]] - s->x[t.a[k]];
		double dy = (double) s->y[t.b[k]] - s->y[t.a[k]];
		double dz = (double) s->z[t.b[k]] - s->z[t.a[k]];
		double rest = (double) t.rest0[k] * ( 1.0 - shrink );
		worst = fmax( worst, fabs( sqrt( dx * dx + dy * dy + dz * dz ) / rest - 1.0 ) );
	}
	return worst;
}

Test( massspring, mass_from_gray_is_logarithmic )
{
	float gray[256], mass[256];
	for ( int g = 0; g < 256; ++g )
	{
		gray[g] = (float) g / 255.0f;
	}
	cr_assert_eq( sere_massspring_mass_from_gray( gray, 256, 0.1f, 1.0f, mass ), SERE_OK );
	/* Black and white are the ends of the range (float rounding of m_min + (m_max − m_min)·1). */
	cr_expect_eq( mass[0], 0.1f );
	cr_expect_float_eq( mass[255], 1.0f, 1e-6f );
	for ( int g = 1; g < 256; ++g )
	{
		cr_expect( mass[g] > mass[g - 1], "mass must rise with the gray value (%d)", g );
	}
	/* Tang Eq. 3 as documented: mid gray G = 127.5 gives 0.1 + 0.9 ln(128.5)/ln(256). */
	float mid = 0.5f, m;
	cr_assert_eq( sere_massspring_mass_from_gray( &mid, 1, 0.1f, 1.0f, &m ), SERE_OK );
	cr_expect_float_eq( m, (float) ( 0.1 + 0.9 * log( 128.5 ) / log( 256.0 ) ), 1e-6f );
	/* Logarithmic: the darkest tenth of the gray range covers more than half of the masses. */
	cr_expect( mass[26] - mass[0] > 0.5f * ( mass[255] - mass[0] ) );
	/* Out-of-range grays are clamped; NaN and a bad mass range are refused. */
	float odd[2] = { -3.0f, 7.0f }, om[2];
	cr_assert_eq( sere_massspring_mass_from_gray( odd, 2, 0.1f, 1.0f, om ), SERE_OK );
	cr_expect_eq( om[0], 0.1f );
	cr_expect_eq( om[1], mass[255] );
	float nan_gray = NAN;
	cr_expect_eq( sere_massspring_mass_from_gray( &nan_gray, 1, 0.1f, 1.0f, &m ), SERE_ERR_NONFINITE );
	cr_expect_eq( sere_massspring_mass_from_gray( gray, 1, 0.0f, 1.0f, &m ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_massspring_mass_from_gray( gray, 1, 2.0f, 1.0f, &m ), SERE_ERR_ARGUMENT );
}

Test( massspring, springs_of_a_mesh )
{
	sheet s = sheet_make( 9, 0.0f );
	sere_massspring* ms = sheet_springs( &s );
	sere_massspring_topology t = sere_massspring_get_topology( ms );
	/* A disk: V − E + F = 1, so E = V + F − 1; every edge off the 4n boundary edges is a hinge. */
	const int32_t edges = s.vertex_count + s.triangle_count - 1;
	cr_expect_eq( t.structural_count, edges );
	cr_expect_eq( t.flexion_count, edges - 4 * s.n );
	cr_expect_eq( t.run_count, ( 2 * t.band_count - 1 ) * t.color_count );
	cr_expect_eq( t.run_offsets[0], 0 );
	cr_expect_eq( t.run_offsets[t.run_count], t.structural_count );
	/* Springs of one run never share a particle (so they are limited at the same time). */
	uint8_t* seen = calloc( (size_t) s.vertex_count, 1 );
	for ( int32_t r = 0; r < t.run_count; ++r )
	{
		memset( seen, 0, (size_t) s.vertex_count );
		for ( int32_t k = t.run_offsets[r]; k < t.run_offsets[r + 1]; ++k )
		{
			cr_expect( t.a[k] < t.b[k] );
			cr_expect( !seen[t.a[k]] && !seen[t.b[k]], "run %d shares a particle", r );
			seen[t.a[k]] = seen[t.b[k]] = 1;
		}
	}
	/* Within each phase of a sweep (the bands, the even cuts, the odd cuts) the items, which
	 * threads take in parallel, share no particle: that makes the sweep's result the same for
	 * any thread count. */
	int32_t* owner = malloc( sizeof( int32_t ) * (size_t) s.vertex_count );
	const int32_t bands = t.band_count, phase_start[4] = { 0, bands, bands + bands / 2, 2 * bands - 1 };
	for ( int phase = 0; phase < 3; ++phase )
	{
		for ( int32_t i = 0; i < s.vertex_count; ++i )
		{
			owner[i] = -1;
		}
		for ( int32_t item = phase_start[phase]; item < phase_start[phase + 1]; ++item )
		{
			for ( int32_t k = t.run_offsets[item * t.color_count]; k < t.run_offsets[( item + 1 ) * t.color_count];
				  ++k )
			{
				const int32_t ends[2] = { t.a[k], t.b[k] };
				for ( int e = 0; e < 2; ++e )
				{
					cr_expect( owner[ends[e]] < 0 || owner[ends[e]] == item, "phase %d: items %d and %d share %d",
							   phase, owner[ends[e]], item, ends[e] );
					owner[ends[e]] = item;
				}
			}
		}
	}
	free( owner );
	/* Natural lengths are the rest-shape distances: cell edges 1/9, diagonals √2/9, and the
	 * flexion springs across a diagonal join two cell corners √2/9 apart or across a cell side. */
	for ( int32_t k = 0; k < t.structural_count; ++k )
	{
		float r = t.rest0[k] * 9.0f;
		cr_expect( fabsf( r - 1.0f ) < 1e-5f || fabsf( r - sqrtf( 2.0f ) ) < 1e-5f, "rest %g", (double) r );
	}
	free( seen );
	sere_massspring_destroy( ms );
	sheet_free( &s );
}

/* A flag: the sheet pinned along its bottom row, pulled down hard. Without the limit the
 * springs near the pins stretch past 10%; with it no spring leaves the band after any step. */
Test( massspring, strain_limit_holds_every_step, .timeout = 60 )
{
	sere_massspring_params params = sere_massspring_params_default();
	params.gravity[2] = -30.0f;
	double unlimited = 0.0;
	for ( int pass = 0; pass < 2; ++pass )
	{
		sheet s = sheet_make( 16, 0.05f );
		for ( int32_t i = 0; i <= s.n; ++i )
		{
			s.inv_m[i] = 0.0f;
		}
		sere_massspring* ms = sheet_springs( &s );
		sere_massspring_particles p = sheet_particles( &s );
		params.strain_limit = pass == 0 ? 0.9f : 0.1f;
		int32_t limited_steps = 0;
		for ( int step = 0; step < 250; ++step )
		{
			sere_massspring_report report;
			cr_assert_eq( sere_massspring_step( ms, &p, &params, &report ), SERE_OK, "step %d", step );
			double strain = max_strain( ms, &s, 0.0f );
			if ( pass == 0 )
			{
				unlimited = fmax( unlimited, strain );
				continue;
			}
			/* The kernel keeps every spring inside [0.9 L, 1.1 L] in float; recomputing the
			 * lengths in double from float positions of size ~1 adds at most ~1e-7 / L = 2e-6. */
			cr_assert( strain <= 0.1 + 1e-5, "step %d: strain %.7f", step, strain );
			cr_assert( fabs( report.max_strain - strain ) <= 1e-5 );
			limited_steps += report.limited > 0;
		}
		if ( pass == 1 )
		{
			cr_expect( limited_steps > 100, "the limit acted in only %d steps", limited_steps );
		}
		sere_massspring_destroy( ms );
		sheet_free( &s );
	}
	cr_expect( unlimited > 0.15, "the forces are too weak to test the limit (strain %.3f)", unlimited );
}

/* The lower side of the band: a sheet squeezed to 80% of its natural size is back within 10%
 * after one step. */
Test( massspring, compressed_springs_return_to_the_band )
{
	sheet s = sheet_make( 12, 0.0f );
	sere_massspring* ms = sheet_springs( &s );
	for ( int32_t v = 0; v < s.vertex_count; ++v )
	{
		s.x[v] *= 0.8f;
		s.y[v] *= 0.8f;
	}
	cr_assert( max_strain( ms, &s, 0.0f ) > 0.19 );
	sere_massspring_params params = sere_massspring_params_default();
	params.gravity[2] = 0.0f;
	sere_massspring_particles p = sheet_particles( &s );
	sere_massspring_report report;
	cr_assert_eq( sere_massspring_step( ms, &p, &params, &report ), SERE_OK );
	/* Nearly all springs need the limit (a few are pulled back by their neighbours' corrections
	 * before the sweep reaches them). */
	cr_expect( report.limited > 9 * sere_massspring_get_topology( ms ).structural_count / 10, "limited %d",
			   report.limited );
	cr_expect( max_strain( ms, &s, 0.0f ) <= 0.1 + 1e-5 );
	sere_massspring_destroy( ms );
	sheet_free( &s );
}

/* Mean displacement from the rest shape of the vertices left and right of x = 0 (the middle
 * column excluded). */
static void side_displacements( const sheet* s, const sheet* rest, double* left, double* right )
{
	double l = 0.0, r = 0.0;
	int nl = 0, nr = 0;
	for ( int32_t v = 0; v < s->vertex_count; ++v )
	{
		double d = sqrt( pow( (double) s->x[v] - rest->x[v], 2 ) + pow( (double) s->y[v] - rest->y[v], 2 ) +
						 pow( (double) s->z[v] - rest->z[v], 2 ) );
		if ( rest->x[v] < -1e-6f )
		{
			l += d, ++nl;
		}
		else if ( rest->x[v] > 1e-6f )
		{
			r += d, ++nr;
		}
	}
	*left = l / nl;
	*right = r / nr;
}

/* Sec. 4.2: "the leaf regions with darker gray values are deformed more than the regions with
 * brighter gray values". The same drying forces (contracting and curling springs) act on a
 * sheet whose left half is painted dark and right half white. */
Test( massspring, darker_regions_move_more )
{
	sere_massspring_params params = sere_massspring_params_default();
	params.gravity[2] = 0.0f;
	params.shrink = 0.03f;
	params.curl = 0.15f;
	double ratio[2];
	for ( int painted = 0; painted < 2; ++painted )
	{
		sheet s = sheet_make( 16, 0.05f ), rest = sheet_make( 16, 0.05f );
		float* gray = malloc( (size_t) s.vertex_count * sizeof( float ) );
		float* mass = malloc( (size_t) s.vertex_count * sizeof( float ) );
		for ( int32_t v = 0; v < s.vertex_count; ++v )
		{
			gray[v] = painted && s.x[v] < 0.0f ? 0.02f : 1.0f;
		}
		cr_assert_eq( sere_massspring_mass_from_gray( gray, s.vertex_count, 0.1f, 1.0f, mass ), SERE_OK );
		for ( int32_t v = 0; v < s.vertex_count; ++v )
		{
			s.inv_m[v] = 1.0f / mass[v];
		}
		sere_massspring* ms = sheet_springs( &s );
		sere_massspring_particles p = sheet_particles( &s );
		for ( int step = 0; step < 150; ++step )
		{
			cr_assert_eq( sere_massspring_step( ms, &p, &params, NULL ), SERE_OK );
		}
		double left, right;
		side_displacements( &s, &rest, &left, &right );
		cr_assert( right > 1e-4, "the forces did not move the sheet" );
		ratio[painted] = left / right;
		sere_massspring_destroy( ms );
		sheet_free( &s );
		sheet_free( &rest );
		free( gray );
		free( mass );
	}
	/* Unpainted, the mirror-symmetric sheet moves alike on both sides (up to the order of
	 * float sums, which the mesh's vertex numbering does not mirror). */
	cr_expect( fabs( ratio[0] - 1.0 ) < 0.02, "uniform mask: left/right %.4f", ratio[0] );
	cr_expect( ratio[1] > 1.5, "dark half moved only %.3f times as far as the white half", ratio[1] );
}

/* The optimized kernel against the scalar twin, stepping the same flag under moderate gravity
 * so that the limit acts at times. */
/* The kernel against its serial twin on a sheet of n × n cells (one band for 14, four for 48). */
static void match_twin( int32_t n )
{
	sheet s = sheet_make( n, 0.05f ), r = sheet_make( n, 0.05f );
	for ( int32_t i = 0; i <= s.n; ++i )
	{
		s.inv_m[i] = r.inv_m[i] = 0.0f;
	}
	for ( int32_t v = s.n + 1; v < s.vertex_count; ++v )
	{
		s.inv_m[v] = r.inv_m[v] = 1.0f / ( 0.2f + 0.8f * (float) ( v % 7 ) / 6.0f );
	}
	sere_massspring* ms = sheet_springs( &s );
	sere_massspring_topology t = sere_massspring_get_topology( ms );
	float* scratch = malloc( 3 * (size_t) s.vertex_count * sizeof( float ) );
	sere_massspring_params params = sere_massspring_params_default();
	params.gravity[2] = -12.0f;
	params.curl = 0.05f;
	sere_massspring_particles p = sheet_particles( &s ), q = sheet_particles( &r );
	double worst = 0.0;
	int32_t limited = 0;
	for ( int step = 0; step < 120; ++step )
	{
		sere_massspring_report a, b;
		cr_assert_eq( sere_massspring_step( ms, &p, &params, &a ), SERE_OK );
		cr_assert_eq( sere_massspring_ref_step( &t, &q, &params, scratch, scratch + s.vertex_count,
												scratch + 2 * s.vertex_count, &b ),
					  SERE_OK );
		limited += a.limited;
		for ( int32_t v = 0; v < s.vertex_count; ++v )
		{
			worst = fmax( worst, fabs( (double) s.x[v] - r.x[v] ) + fabs( (double) s.y[v] - r.y[v] ) +
									 fabs( (double) s.z[v] - r.z[v] ) );
		}
	}
	cr_expect( limited > 0, "the limit never acted" );
	/* Both sweep the structural springs in the same order with the same arithmetic; they differ
	 * in how the force sums are grouped (a per-particle gather against a scatter in spring order),
	 * ~1e-7 relative per step. Over 120 steps that stays below 1e-5 of the 1-long sheet unless a
	 * sweep count flips at the tolerance; 5e-5 = δ L (δ = 1e-3, L ≈ 0.07) allows one such flip. */
	cr_expect( worst <= 5e-5, "kernel and twin differ by %g", worst );
	free( scratch );
	sere_massspring_destroy( ms );
	sheet_free( &s );
	sheet_free( &r );
}

Test( massspring, matches_the_reference_twin )
{
	match_twin( 14 );
	match_twin( 48 );
}

/* A sheet hanging from one corner: long chains at the limit, many sweeps and colors. */
Test( massspring, one_and_two_threads_bitwise_equal )
{
	/* 13 x 13 particles make one band; 49 x 49 make four, so the sweep's band and cut phases
	 * run on threads that split them differently (1, 2 and 3 threads). */
	const int32_t sizes[2] = { 12, 48 };
	for ( int size = 0; size < 2; ++size )
	{
		sheet s[3];
		sere_massspring_params params = sere_massspring_params_default();
		params.gravity[2] = -20.0f;
		params.curl = 0.1f;
		for ( int k = 0; k < 3; ++k )
		{
			s[k] = sheet_make( sizes[size], 0.05f );
			s[k].inv_m[0] = 0.0f;
			sere_massspring* ms = sheet_springs( &s[k] );
			if ( size == 1 )
			{
				cr_expect_gt( sere_massspring_get_topology( ms ).band_count, 2 );
			}
			sere_massspring_particles p = sheet_particles( &s[k] );
			omp_set_num_threads( k + 1 );
			for ( int step = 0; step < 60; ++step )
			{
				cr_assert_eq( sere_massspring_step( ms, &p, &params, NULL ), SERE_OK );
			}
			sere_massspring_destroy( ms );
		}
		omp_set_num_threads( 1 );
		size_t bytes = (size_t) s[0].vertex_count * sizeof( float );
		for ( int k = 1; k < 3; ++k )
		{
			cr_expect_eq( memcmp( s[0].x, s[k].x, bytes ), 0, "%d particles, %d threads", s[0].vertex_count, k + 1 );
			cr_expect_eq( memcmp( s[0].y, s[k].y, bytes ), 0 );
			cr_expect_eq( memcmp( s[0].z, s[k].z, bytes ), 0 );
			cr_expect_eq( memcmp( s[0].vx, s[k].vx, bytes ), 0 );
			cr_expect_eq( memcmp( s[0].vz, s[k].vz, bytes ), 0 );
		}
		/* Free fall would take the far corner 0.036 below its start of 0.025 in 60 steps. */
		cr_expect( s[0].z[s[0].vertex_count - 1] < 0.0f, "the sheet did not fall" );
		for ( int k = 0; k < 3; ++k )
		{
			sheet_free( &s[k] );
		}
	}
	omp_set_num_threads( 2 );
}

Test( massspring, sweep_cap_is_reported )
{
	sheet s = sheet_make( 12, 0.0f );
	sere_massspring* ms = sheet_springs( &s );
	for ( int32_t v = 0; v < s.vertex_count; ++v )
	{
		s.x[v] *= 0.7f;
	}
	sere_massspring_params params = sere_massspring_params_default();
	params.max_sweeps = 1;
	sere_massspring_particles p = sheet_particles( &s );
	sere_massspring_report report;
	cr_expect_eq( sere_massspring_step( ms, &p, &params, &report ), SERE_ERR_NO_CONVERGE );
	cr_expect_eq( report.hit_cap, 1 );
	cr_expect_eq( report.sweeps, 1 );
	sere_massspring_destroy( ms );
	sheet_free( &s );
}

Test( massspring, bad_meshes_are_refused )
{
	sere_massspring* ms = (sere_massspring*) 1;
	float x[5] = { 0, 1, 0, 1, 0.5f }, y[5] = { 0, 0, 1, 1, -1 }, z[5] = { 0 };
	int32_t good[6] = { 0, 1, 2, 1, 3, 2 };
	cr_assert_eq( sere_massspring_create( x, y, z, 5, good, 2, &ms ), SERE_OK );
	sere_massspring_destroy( ms );

	int32_t out_of_range[3] = { 0, 1, 5 };
	cr_expect_eq( sere_massspring_create( x, y, z, 5, out_of_range, 1, &ms ), SERE_ERR_ARGUMENT );
	cr_expect_null( ms );
	int32_t repeated[3] = { 0, 1, 1 };
	cr_expect_eq( sere_massspring_create( x, y, z, 5, repeated, 1, &ms ), SERE_ERR_ARGUMENT );
	/* Three triangles on the edge 0–1: not a surface. */
	int32_t fan[9] = { 0, 1, 2, 1, 0, 4, 0, 1, 3 };
	cr_expect_eq( sere_massspring_create( x, y, z, 5, fan, 3, &ms ), SERE_ERR_GEOMETRY );
	float xd[5] = { 0, 0, 0, 1, 0.5f }, yd[5] = { 0, 0, 1, 1, -1 };
	cr_expect_eq( sere_massspring_create( xd, yd, z, 5, good, 2, &ms ), SERE_ERR_GEOMETRY );
	float xn[5] = { 0, 1, NAN, 1, 0.5f };
	cr_expect_eq( sere_massspring_create( xn, y, z, 5, good, 2, &ms ), SERE_ERR_NONFINITE );
	cr_expect_eq( sere_massspring_create( x, y, z, 5, good, 0, &ms ), SERE_ERR_ARGUMENT );
	/* three sides a triangle would pass INT32_MAX (refused before a triangle is read) */
	cr_expect_eq( sere_massspring_create( x, y, z, 5, good, INT32_MAX / 3 + 1, &ms ), SERE_ERR_ARGUMENT );
}

Test( massspring, bad_steps_change_nothing )
{
	sheet s = sheet_make( 6, 0.02f );
	sere_massspring* ms = sheet_springs( &s );
	sere_massspring_particles p = sheet_particles( &s );
	sere_massspring_params params = sere_massspring_params_default();
	size_t bytes = (size_t) s.vertex_count * sizeof( float );
	float* before = malloc( bytes );
	memcpy( before, s.z, bytes );

	s.vx[5] = NAN;
	cr_expect_eq( sere_massspring_step( ms, &p, &params, NULL ), SERE_ERR_NONFINITE );
	s.vx[5] = 0.0f;
	s.inv_m[3] = -1.0f;
	cr_expect_eq( sere_massspring_step( ms, &p, &params, NULL ), SERE_ERR_ARGUMENT );
	s.inv_m[3] = 1.0f;
	cr_expect_eq( memcmp( before, s.z, bytes ), 0 );

	sere_massspring_params bad = params;
	bad.dt = 0.0f;
	cr_expect_eq( sere_massspring_step( ms, &p, &bad, NULL ), SERE_ERR_ARGUMENT );
	bad = params;
	bad.strain_limit = 1.5f;
	cr_expect_eq( sere_massspring_step( ms, &p, &bad, NULL ), SERE_ERR_ARGUMENT );
	bad = params;
	bad.strain_tolerance = bad.strain_limit;
	cr_expect_eq( sere_massspring_step( ms, &p, &bad, NULL ), SERE_ERR_ARGUMENT );
	bad = params;
	bad.drag = 1.0f;
	cr_expect_eq( sere_massspring_step( ms, &p, &bad, NULL ), SERE_ERR_ARGUMENT );
	bad = params;
	bad.gravity[1] = INFINITY;
	cr_expect_eq( sere_massspring_step( ms, &p, &bad, NULL ), SERE_ERR_ARGUMENT );
	bad = params;
	bad.max_sweeps = 0;
	cr_expect_eq( sere_massspring_step( ms, &p, &bad, NULL ), SERE_ERR_ARGUMENT );
	p.count -= 1;
	cr_expect_eq( sere_massspring_step( ms, &p, &params, NULL ), SERE_ERR_ARGUMENT );
	cr_expect_eq( memcmp( before, s.z, bytes ), 0 );

	free( before );
	sere_massspring_destroy( ms );
	sheet_free( &s );
}

/* The floor (sere_massspring_touch) moves a step's memory but must not move the leaf: after real
 * steps of a blade pinned at one corner (velocities nonzero, the pinned one's zero), the touch at 1
 * and 2 threads leaves every position and velocity equal to what it was (compared with ==: Δt = 0
 * adds exact zeros), and bad input is refused with nothing changed. */
Test( massspring, touch_leaves_the_particles_as_they_were )
{
	sheet s = sheet_make( 8, 0.02f );
	s.inv_m[0] = 0.0f;
	sere_massspring* ms = sheet_springs( &s );
	sere_massspring_particles p = sheet_particles( &s );
	sere_massspring_params params = sere_massspring_params_default();
	params.shrink = 0.05f;
	params.curl = 0.2f;
	for ( int step = 0; step < 20; ++step )
	{
		sere_status status = sere_massspring_step( ms, &p, &params, NULL );
		cr_assert( status == SERE_OK || status == SERE_ERR_NO_CONVERGE );
	}
	const int32_t n = s.vertex_count;
	float* arrays[6] = { s.x, s.y, s.z, s.vx, s.vy, s.vz };
	float* before = malloc( 6 * (size_t) n * sizeof( float ) );
	cr_assert_not_null( before );
	for ( int k = 0; k < 6; ++k )
	{
		memcpy( before + (size_t) k * n, arrays[k], (size_t) n * sizeof( float ) );
	}
	cr_assert_neq( s.vz[n - 1], 0.0f, "the free corner moves, so a touch that zeroed velocities would show" );
	for ( int32_t threads = 1; threads <= 2; ++threads )
	{
		cr_assert_eq( sere_massspring_set_threads( ms, threads ), SERE_OK );
		cr_assert_eq( sere_massspring_touch( ms, &p, 7 ), SERE_OK );
		for ( int k = 0; k < 6; ++k )
		{
			for ( int32_t i = 0; i < n; ++i )
			{
				cr_assert_eq( arrays[k][i], before[(size_t) k * n + i], "array %d particle %d at %d threads", k, i,
							  threads );
			}
		}
	}
	cr_expect_eq( sere_massspring_touch( ms, &p, 0 ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_massspring_touch( NULL, &p, 1 ), SERE_ERR_ARGUMENT );
	p.count -= 1;
	cr_expect_eq( sere_massspring_touch( ms, &p, 1 ), SERE_ERR_ARGUMENT );
	p.count += 1;
	s.y[4] = NAN;
	cr_expect_eq( sere_massspring_touch( ms, &p, 1 ), SERE_ERR_NONFINITE );
	s.y[4] = before[(size_t) n + 4];
	cr_expect_eq( memcmp( before, s.x, (size_t) n * sizeof( float ) ), 0 );

	free( before );
	sere_massspring_destroy( ms );
	sheet_free( &s );
}

static uint64_t fnv1a( uint64_t h, const void* data, size_t bytes )
{
	const unsigned char* p = data;
	for ( size_t i = 0; i < bytes; ++i )
	{
		h = ( h ^ p[i] ) * 0x100000001b3ull;
	}
	return h;
}

/* The step is written once over the SIMD lane layer (kernels/core/internal/simd.h), built at
 * 16 lanes (AVX-512), 8 (AVX2) or 4 (portable C). Lane-wise IEEE arithmetic without FMA gives
 * every width the same bits, and the same bits the three hand-written bodies gave before the
 * layer: the hash below was taken from those (commit 9b87f30, AVX-512 build) and CI checks it
 * with the AVX2 and portable builds too (make test-widths). */
Test( massspring, same_bits_at_every_simd_width )
{
	sheet s = sheet_make( 48, 0.05f );
	for ( int32_t v = 0; v < s.vertex_count; ++v )
	{
		s.inv_m[v] = v <= s.n ? 0.0f : 1.0f / ( 0.2f + 0.8f * (float) ( v % 7 ) / 6.0f );
	}
	sere_massspring* ms = sheet_springs( &s );
	sere_massspring_params params = sere_massspring_params_default();
	params.gravity[2] = -20.0f;
	params.curl = 0.1f;
	sere_massspring_particles p = sheet_particles( &s );
	int32_t limited = 0;
	for ( int step = 0; step < 60; ++step )
	{
		sere_massspring_report report;
		cr_assert_eq( sere_massspring_step( ms, &p, &params, &report ), SERE_OK );
		limited += report.limited;
	}
	cr_expect( limited > 0, "the strain limit (Tang Eq. 2) never acted, so its body went untested" );
	size_t bytes = (size_t) s.vertex_count * sizeof( float );
	uint64_t h = 0xcbf29ce484222325ull;
	const float* fields[6] = { s.x, s.y, s.z, s.vx, s.vy, s.vz };
	for ( int f = 0; f < 6; ++f )
	{
		h = fnv1a( h, fields[f], bytes );
	}
	cr_expect_eq( h, 0x2fd832dd4081ee6aull, "hash %#018llx", (unsigned long long) h );
	sere_massspring_destroy( ms );
	sheet_free( &s );
}
