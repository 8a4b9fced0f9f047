/* Tests of the venation skeleton kernels (seed 003: Lu, Zhao, Guo 2009): subdivision, leaf and
 * venation skeletons, banding against brute force; the pose, skinning and the plant are in
 * test_skeleton_pose.c. */
#include "fixture.h"
#include "mesh/subdivide.h"
#include "ref/skeleton_ref.h"
#include "skeleton_leaf.h"
#include "wilt/skeleton.h"

#include <criterion/criterion.h>
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

/* Signed area of a triangle in the plane. */
static double area2d( const sere_tri_mesh* m, int32_t t )
{
	const int32_t* c = m->tri + 3 * t;
	return 0.5 * ( ( (double) m->x[c[1]] - m->x[c[0]] ) * ( (double) m->y[c[2]] - m->y[c[0]] ) -
				   ( (double) m->x[c[2]] - m->x[c[0]] ) * ( (double) m->y[c[1]] - m->y[c[0]] ) );
}

/* Undirected edges with their use counts: sorted keys, so duplicates are adjacent. */
static int compare_u64( const void* a, const void* b )
{
	uint64_t p = *(const uint64_t*) a, q = *(const uint64_t*) b;
	return ( p > q ) - ( p < q );
}

static void edge_uses( const sere_tri_mesh* m, int32_t* edges, int32_t* boundary, int32_t* over_used )
{
	int32_t n = 3 * m->triangle_count;
	uint64_t* keys = malloc( (size_t) n * sizeof( uint64_t ) );
	for ( int32_t s = 0; s < n; ++s )
	{
		uint32_t a = (uint32_t) m->tri[s], b = (uint32_t) m->tri[( s / 3 ) * 3 + ( s % 3 + 1 ) % 3];
		keys[s] = a < b ? ( (uint64_t) a << 32 ) | b : ( (uint64_t) b << 32 ) | a;
	}
	qsort( keys, (size_t) n, sizeof( uint64_t ), compare_u64 );
	*edges = *boundary = *over_used = 0;
	for ( int32_t s = 0; s < n; )
	{
		int32_t e = s;
		while ( e < n && keys[e] == keys[s] )
		{
			++e;
		}
		++*edges;
		*boundary += e - s == 1;
		*over_used += e - s > 2;
		s = e;
	}
	free( keys );
}

/* ------------------------------------------------------------------------------------------- */

Test( subdivide, uniform_one_to_four )
{
	sere_tri_mesh in, out;
	skeleton_grid_leaf( &in, 10.0, 6.0, 0.0, 20, 12 );
	/* Texture coordinates are an affine function of position; midpoints must keep that. */
	int32_t e0, b0, o0;
	edge_uses( &in, &e0, &b0, &o0 );
	cr_assert_eq( sere_subdivide( &in, 2, 0.0f, &out ), SERE_OK );
	/* Pass 1 adds one vertex per edge and makes 4 triangles of each; pass 2 again, on a mesh of
	 * 2E + 3F edges. */
	int32_t e1 = 2 * e0 + 3 * in.triangle_count, v1 = in.vertex_count + e0;
	cr_expect_eq( out.vertex_count, v1 + e1 );
	cr_expect_eq( out.triangle_count, 16 * in.triangle_count );
	int32_t e2, b2, o2;
	edge_uses( &out, &e2, &b2, &o2 );
	cr_expect_eq( o2, 0, "no edge is shared by more than two triangles" );
	cr_expect_eq( b2, 4 * b0, "every boundary edge is cut in four" );
	cr_expect_eq( (int64_t) out.vertex_count - e2 + out.triangle_count,
				  (int64_t) in.vertex_count - e0 + in.triangle_count, "Euler characteristic kept" );
	double a_in = 0.0, a_out = 0.0;
	for ( int32_t t = 0; t < in.triangle_count; ++t )
	{
		a_in += area2d( &in, t );
	}
	for ( int32_t t = 0; t < out.triangle_count; ++t )
	{
		cr_assert_gt( area2d( &out, t ), 0.0, "orientation kept" );
		a_out += area2d( &out, t );
	}
	/* Midpoints of float coordinates are exact in float for this grid (dyadic steps), so only the
	 * summation order differs: 1e-9 relative. */
	cr_expect_float_eq( a_out, a_in, 1e-9 * a_in );
	for ( int32_t i = 0; i < out.vertex_count; ++i )
	{
		/* u = x / 10 and v = (y + 3) / 6 at the grid vertices; float rounding of both sides
		 * stays below 1e-6. */
		cr_assert_float_eq( out.u[i], out.x[i] / 10.0f, 1e-6f );
		cr_assert_float_eq( out.v[i], ( out.y[i] + 3.0f ) / 6.0f, 1e-6f );
	}
	sere_tri_mesh_destroy( &in );
	sere_tri_mesh_destroy( &out );
}

Test( subdivide, minimal_edge_length )
{
	sere_tri_mesh in, out;
	skeleton_grid_leaf( &in, 10.0, 6.0, 0.3, 16, 12 );
	/* Jitter the vertices so edge lengths spread around the threshold. */
	uint64_t seed = 5;
	for ( int32_t i = 0; i < in.vertex_count; ++i )
	{
		in.x[i] += (float) ( 0.15 * ( sere_test_unit( &seed ) - 0.5 ) );
		in.y[i] += (float) ( 0.15 * ( sere_test_unit( &seed ) - 0.5 ) );
	}
	float min_edge = 0.3f;
	/* The edges long enough to cut: both halves at least min_edge. */
	int32_t long_edges = 0, e0, b0, o0;
	edge_uses( &in, &e0, &b0, &o0 );
	for ( int32_t s = 0; s < 3 * in.triangle_count; ++s )
	{
		int32_t a = in.tri[s], b = in.tri[( s / 3 ) * 3 + ( s % 3 + 1 ) % 3];
		double d = hypot( (double) in.x[a] - in.x[b], (double) in.y[a] - in.y[b] );
		/* each interior edge appears twice, once from each side */
		long_edges += d >= 2.0 * min_edge;
	}
	cr_assert_eq( sere_subdivide( &in, 1, min_edge, &out ), SERE_OK );
	int32_t cut = out.vertex_count - in.vertex_count;
	cr_expect_gt( cut, 0 );
	cr_expect_lt( cut, e0, "some edges are too short to cut" );
	int32_t e1, b1, o1;
	edge_uses( &out, &e1, &b1, &o1 );
	cr_expect_eq( o1, 0 );
	/* Conforming: each cut edge (counted once per side in long_edges) gives one vertex, and the
	 * boundary grows by exactly the cut boundary edges, so no hanging vertex is left. */
	int32_t boundary_cut = 0;
	for ( int32_t i = in.vertex_count; i < out.vertex_count; ++i )
	{
		cr_assert( isfinite( out.x[i] ) );
	}
	cr_expect_eq( (int64_t) out.vertex_count - e1 + out.triangle_count,
				  (int64_t) in.vertex_count - e0 + in.triangle_count );
	boundary_cut = b1 - b0;
	cr_expect_eq( 2 * cut, long_edges + boundary_cut, "interior cut edges counted twice, boundary ones once" );
	for ( int32_t t = 0; t < out.triangle_count; ++t )
	{
		cr_assert_gt( area2d( &out, t ), 0.0 );
	}
	sere_tri_mesh_destroy( &in );
	sere_tri_mesh_destroy( &out );
}

Test( subdivide, rejects_bad_input )
{
	sere_tri_mesh in, out;
	skeleton_grid_leaf( &in, 10.0, 6.0, 0.0, 4, 4 );
	cr_expect_eq( sere_subdivide( &in, -1, 0.0f, &out ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_subdivide( &in, 9, 0.0f, &out ), SERE_ERR_ARGUMENT );
	in.x[1] = NAN;
	cr_expect_eq( sere_subdivide( &in, 1, 0.0f, &out ), SERE_ERR_NONFINITE );
	in.x[1] = 0.0f;
	in.tri[4] = in.vertex_count;
	cr_expect_eq( sere_subdivide( &in, 1, 0.0f, &out ), SERE_ERR_ARGUMENT );
	sere_tri_mesh_destroy( &in );
}

/* ------------------------------------------------------------------------------------------- */

/* The blade mesh is a disc (Euler characteristic 1), counter-clockwise, manifold, and its
 * boundary follows the sampled outline: no boundary edge is longer than the sampling allows, as
 * one would be if a triangle bridged a notch of a concave outline. */
static void expect_blade( const sere_tri_mesh* m, double spacing )
{
	int32_t edges, boundary, over_used;
	edge_uses( m, &edges, &boundary, &over_used );
	cr_expect_eq( over_used, 0 );
	cr_expect_eq( (int64_t) m->vertex_count - edges + m->triangle_count, 1, "a disc" );
	float lo[2] = { INFINITY, INFINITY }, hi[2] = { -INFINITY, -INFINITY };
	for ( int32_t i = 0; i < m->vertex_count; ++i )
	{
		cr_assert_eq( m->z[i], 0.0f );
		lo[0] = fminf( lo[0], m->u[i] );
		lo[1] = fminf( lo[1], m->v[i] );
		hi[0] = fmaxf( hi[0], m->u[i] );
		hi[1] = fmaxf( hi[1], m->v[i] );
	}
	/* The outline's bounding box maps to [0, 1]²: float rounding 1e-6. */
	cr_expect_float_eq( lo[0], 0.0f, 1e-6f );
	cr_expect_float_eq( lo[1], 0.0f, 1e-6f );
	cr_expect_float_eq( hi[0], 1.0f, 1e-6f );
	cr_expect_float_eq( hi[1], 1.0f, 1e-6f );
	for ( int32_t t = 0; t < m->triangle_count; ++t )
	{
		cr_assert_gt( area2d( m, t ), 0.0, "triangle %d counter-clockwise", t );
	}
	/* Boundary edges: each used once; the outline is sampled every `spacing` of arc, so a chord
	 * is at most that long (1.5 allows for float rounding and the curve's resampling). */
	int32_t n = 3 * m->triangle_count;
	for ( int32_t s = 0; s < n; ++s )
	{
		int32_t a = m->tri[s], b = m->tri[( s / 3 ) * 3 + ( s % 3 + 1 ) % 3];
		int shared = 0;
		for ( int32_t q = 0; q < n && !shared; ++q )
		{
			shared = m->tri[q] == b && m->tri[( q / 3 ) * 3 + ( q % 3 + 1 ) % 3] == a;
		}
		if ( !shared )
		{
			cr_assert_leq( hypot( (double) m->x[a] - m->x[b], (double) m->y[a] - m->y[b] ), 1.5 * spacing,
						   "boundary edge %d-%d", a, b );
		}
	}
}

Test( skeleton, blade_meshes_convex_and_lobed_outlines )
{
	double l[18], r[18], m[18];
	sere_leaf_skeleton leaf;
	skeleton_parametric_leaf( l, r, m, &leaf );
	sere_tri_mesh blade;
	sere_skeleton_check check;
	cr_assert_eq( sere_leaf_skeleton_mesh( &leaf, 0.4, &blade, &check ), SERE_OK, "%s",
				  sere_skeleton_problem_text( check.problem ) );
	expect_blade( &blade, 0.4 );
	/* The parametric blade's area is W L (4/15) / (2 / (3√3)) = 0.6928 W L for the exact
	 * profile; the spline through 9 feature points and the sampled outline stay within 3%. */
	double area = 0.0;
	for ( int32_t t = 0; t < blade.triangle_count; ++t )
	{
		area += area2d( &blade, t );
	}
	double exact = 60.0 * ( 4.0 / 15.0 ) / ( sqrt( 1.0 / 3.0 ) * ( 2.0 / 3.0 ) );
	cr_expect_float_eq( area, exact, 0.03 * exact );
	cr_expect_gt( blade.vertex_count, 200, "the interior is filled, not only the outline" );
	sere_tri_mesh_destroy( &blade );

	/* A lobed outline with deep notches (the watermelon of Sec. 7). */
	double lobed[] = { 0.0, 0.0, -0.6, 1.1, 0.2, 2.8, 0.9, 4.6, 2.0, 5.3, 2.8, 4.3, 3.0, 2.4,  3.8,
					   2.6, 4.8, 4.2,  5.9, 4.7, 6.5, 3.6, 6.7, 1.9, 7.6, 1.9, 8.7, 1.5, 10.0, 0.0 };
	double mirrored[30];
	for ( int i = 0; i < 15; ++i )
	{
		mirrored[2 * i] = lobed[2 * i];
		mirrored[2 * i + 1] = -lobed[2 * i + 1];
	}
	double midvein[] = { 0.0, 0.0, 5.0, 0.0, 10.0, 0.0 };
	sere_leaf_skeleton watermelon = { 15, 15, 3, lobed, mirrored, midvein };
	cr_assert_eq( sere_leaf_skeleton_mesh( &watermelon, 0.3, &blade, &check ), SERE_OK, "%s",
				  sere_skeleton_problem_text( check.problem ) );
	expect_blade( &blade, 0.3 );
	/* Nothing in the notch between the basal and the middle lobe, around (3.3, 3.8). */
	for ( int32_t t = 0; t < blade.triangle_count; ++t )
	{
		const int32_t* c = blade.tri + 3 * t;
		double cx = ( (double) blade.x[c[0]] + blade.x[c[1]] + blade.x[c[2]] ) / 3.0;
		double cy = ( (double) blade.y[c[0]] + blade.y[c[1]] + blade.y[c[2]] ) / 3.0;
		cr_assert( !( fabs( cx - 3.3 ) < 0.2 && fabs( fabs( cy ) - 3.8 ) < 0.3 ), "triangle %d in the notch", t );
	}
	sere_tri_mesh_destroy( &blade );
}

Test( skeleton, build_cuts_veins_into_equal_segments )
{
	double mid[] = { 0, 0, 10, 0 };
	double side[] = { 4, 0, 7, 3, 9, 5 }; /* straight, given by three points */
	double far[] = { 7, 3.2, 6, 5 };
	sere_vein_spec veins[3] = { { -1, 10, 1.0f, 2, mid }, { 0, 6, 0.5f, 3, side }, { 1, 2, 0.5f, 2, far } };
	sere_skeleton s;
	sere_skeleton_check check;
	cr_assert_eq( sere_skeleton_create( veins, 3, &s, &check ), SERE_OK );
	cr_expect_eq( s.joint_count, 1 + 10 + 6 + 2 );
	cr_expect_eq( s.vein_count, 3 );
	cr_expect_eq( s.parent[0], -1 );
	cr_expect_eq( s.end[0], s.joint_count );
	double lengths[3] = { 0, 0, 0 };
	int32_t counts[3] = { 0, 0, 0 };
	for ( int32_t i = 1; i < s.joint_count; ++i )
	{
		int32_t p = s.parent[i];
		cr_assert_lt( p, i, "parents precede children" );
		/* Depth-first order: the subtree of every ancestor contains i. */
		for ( int32_t a = p; a >= 0; a = s.parent[a] )
		{
			cr_assert( i > a && i < s.end[a] );
		}
		double d = hypot( (double) s.x[i] - s.x[p], (double) s.y[i] - s.y[p] );
		int32_t v = s.vein[i];
		if ( counts[v] > 0 )
		{
			/* Straight veins cut into equal pieces; float positions: 1e-5. */
			cr_expect_float_eq( d, lengths[v] / counts[v], 1e-5, "vein %d", v );
		}
		lengths[v] += d;
		++counts[v];
		cr_expect_float_eq( s.bend[i], veins[v].bend / veins[v].segments, 1e-7f );
	}
	cr_expect_eq( counts[0], 10 );
	cr_expect_eq( counts[1], 6 );
	cr_expect_eq( counts[2], 2 );
	/* The midvein is 10 long; the side vein starts on midvein joint (4, 0) and runs to (9, 5);
	 * the third hangs from the side vein's joint nearest to (7, 3.2), which is (7.33, 3.33). */
	cr_expect_float_eq( lengths[0], 10.0, 1e-5 );
	cr_expect_float_eq( lengths[1], sqrt( 50.0 ), 1e-5 );
	cr_expect_float_eq( lengths[2], hypot( 6.0 - ( 4.0 + 20.0 / 6.0 ), 5.0 - 20.0 / 6.0 ), 1e-5 );
	/* delay: 1 at the root, 0 at the farthest tip, decreasing along every path. */
	float lowest = 1.0f;
	cr_expect_eq( s.delay[0], 1.0f );
	for ( int32_t i = 1; i < s.joint_count; ++i )
	{
		cr_assert_lt( s.delay[i], s.delay[s.parent[i]] );
		lowest = fminf( lowest, s.delay[i] );
	}
	cr_expect_eq( lowest, 0.0f );
	sere_skeleton_destroy( &s );
}

Test( skeleton, bad_skeletons_name_the_problem )
{
	double mid[] = { 0, 0, 10, 0 };
	double side[] = { 4, 0, 7, 3 };
	double nan_side[] = { 4, 0, NAN, 3 };
	double repeated[] = { 4, 0, 7, 3, 7, 3 };
	double far_away[] = { 4, 40, 5, 41 };
	sere_skeleton s;
	sere_skeleton_check check;
	struct
	{
		sere_vein_spec second;
		int32_t count;
		sere_skeleton_problem problem;
		sere_status status;
		int32_t vein;
	} cases[] = {
		{ { 0, 4, 0.5f, 2, side }, 0, SERE_SKELETON_NO_VEINS, SERE_ERR_GEOMETRY, -1 },
		{ { 1, 4, 0.5f, 2, side }, 2, SERE_SKELETON_BAD_PARENT, SERE_ERR_GEOMETRY, 1 },
		{ { -1, 4, 0.5f, 2, side }, 2, SERE_SKELETON_BAD_PARENT, SERE_ERR_GEOMETRY, 1 },
		{ { 0, 0, 0.5f, 2, side }, 2, SERE_SKELETON_BAD_SEGMENTS, SERE_ERR_GEOMETRY, 1 },
		{ { 0, 5000, 0.5f, 2, side }, 2, SERE_SKELETON_BAD_SEGMENTS, SERE_ERR_GEOMETRY, 1 },
		{ { 0, 4, 0.5f, 1, side }, 2, SERE_SKELETON_FEW_POINTS, SERE_ERR_GEOMETRY, 1 },
		{ { 0, 4, 0.5f, 2, nan_side }, 2, SERE_SKELETON_NONFINITE, SERE_ERR_NONFINITE, 1 },
		{ { 0, 4, NAN, 2, side }, 2, SERE_SKELETON_NONFINITE, SERE_ERR_NONFINITE, 1 },
		{ { 0, 4, 4.0f, 2, side }, 2, SERE_SKELETON_BAD_BEND, SERE_ERR_GEOMETRY, 1 },
		{ { 0, 4, -0.1f, 2, side }, 2, SERE_SKELETON_BAD_BEND, SERE_ERR_GEOMETRY, 1 },
		{ { 0, 4, 0.5f, 3, repeated }, 2, SERE_SKELETON_REPEATED_POINT, SERE_ERR_GEOMETRY, 1 },
		{ { 0, 4, 0.5f, 2, far_away }, 2, SERE_SKELETON_DETACHED, SERE_ERR_GEOMETRY, 1 },
	};
	for ( size_t k = 0; k < sizeof( cases ) / sizeof( cases[0] ); ++k )
	{
		sere_vein_spec veins[2] = { { -1, 10, 1.0f, 2, mid }, cases[k].second };
		check.problem = SERE_SKELETON_OK;
		cr_expect_eq( sere_skeleton_create( cases[k].count ? veins : NULL, cases[k].count, &s, &check ),
					  cases[k].status, "case %zu", k );
		cr_expect_eq( check.problem, cases[k].problem, "case %zu: %s", k, sere_skeleton_problem_text( check.problem ) );
		cr_expect_eq( check.vein, cases[k].vein, "case %zu", k );
		cr_expect_null( s.x, "case %zu leaves nothing allocated", k );
		cr_expect_str_neq( sere_skeleton_problem_text( cases[k].problem ), "unknown problem" );
	}
	/* The midvein itself must have parent -1. */
	sere_vein_spec bad_mid[1] = { { 0, 10, 1.0f, 2, mid } };
	cr_expect_eq( sere_skeleton_create( bad_mid, 1, &s, &check ), SERE_ERR_GEOMETRY );
	cr_expect_eq( check.problem, SERE_SKELETON_BAD_PARENT );
	cr_expect_eq( check.vein, 0 );
}

Test( skeleton, bad_leaf_skeletons_name_the_problem )
{
	double l[18], r[18], m[18];
	sere_leaf_skeleton leaf;
	skeleton_parametric_leaf( l, r, m, &leaf );
	sere_skeleton_check check;
	cr_expect_eq( sere_leaf_skeleton_validate( &leaf, 0.5, &check ), SERE_OK );
	cr_expect_eq( check.problem, SERE_SKELETON_OK );

	cr_expect_eq( sere_leaf_skeleton_validate( &leaf, 0.0, &check ), SERE_ERR_GEOMETRY );
	cr_expect_eq( check.problem, SERE_SKELETON_BAD_SPACING );
	cr_expect_eq( sere_leaf_skeleton_validate( &leaf, 1e-9, &check ), SERE_ERR_GEOMETRY );
	cr_expect_eq( check.problem, SERE_SKELETON_BAD_SPACING );

	/* The right curve's tip pulled away from the others. */
	r[16] = 12.0;
	cr_expect_eq( sere_leaf_skeleton_validate( &leaf, 0.5, &check ), SERE_ERR_GEOMETRY );
	cr_expect_eq( check.problem, SERE_SKELETON_ENDS_APART );
	cr_expect_eq( check.vein, 1 );
	r[16] = 10.0;

	/* The left curve dives through the right one: the outline crosses itself. */
	l[9] = -4.0;
	cr_expect_eq( sere_leaf_skeleton_validate( &leaf, 0.5, &check ), SERE_ERR_GEOMETRY );
	cr_expect_eq( check.problem, SERE_SKELETON_SELF_INTERSECTING );
	l[9] = r[9] * -1.0;

	/* A midvein bulging out of the blade. */
	m[9] = 5.0;
	cr_expect_eq( sere_leaf_skeleton_validate( &leaf, 0.5, &check ), SERE_ERR_GEOMETRY );
	cr_expect_eq( check.problem, SERE_SKELETON_MIDVEIN_OUTSIDE );
	cr_expect_eq( check.vein, 2 );
	m[9] = 0.0;

	m[7] = INFINITY;
	cr_expect_eq( sere_leaf_skeleton_validate( &leaf, 0.5, &check ), SERE_ERR_NONFINITE );
	cr_expect_eq( check.problem, SERE_SKELETON_NONFINITE );
	cr_expect_eq( check.vein, 2 );
	cr_expect_eq( check.point, 3 );
	m[7] = 0.0;

	m[6] = m[4];
	m[7] = m[5];
	cr_expect_eq( sere_leaf_skeleton_validate( &leaf, 0.5, &check ), SERE_ERR_GEOMETRY );
	cr_expect_eq( check.problem, SERE_SKELETON_REPEATED_POINT );
	cr_expect_eq( check.point, 3 );

	leaf.left_count = 1;
	cr_expect_eq( sere_leaf_skeleton_validate( &leaf, 0.5, &check ), SERE_ERR_GEOMETRY );
	cr_expect_eq( check.problem, SERE_SKELETON_FEW_POINTS );
	cr_expect_eq( check.vein, 0 );

	cr_expect_eq( sere_leaf_skeleton_generate( 10.0, -1.0, 9, l, r, m ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_leaf_skeleton_generate( NAN, 1.0, 9, l, r, m ), SERE_ERR_NONFINITE );
	cr_expect_eq( sere_leaf_skeleton_generate( 10.0, 1.0, 2, l, r, m ), SERE_ERR_ARGUMENT );
}

Test( skeleton, generated_venation_matches_the_seed_counts )
{
	/* Sec. 7: the watermelon skeleton has one midvein cut in 30 and four secondary veins cut in
	 * 10; the cucumber one a midvein in 20 and two secondary veins in 4. */
	sere_venation_params p = sere_venation_params_default();
	p.mid_segments = 30;
	p.secondary_count = 4;
	p.secondary_segments = 10;
	sere_skeleton s;
	skeleton_generated( &s, &p );
	cr_expect_eq( s.joint_count, 1 + 30 + 4 * 10 );
	cr_expect_eq( s.vein_count, 5 );
	/* Secondary veins start on midvein joints and stay inside the blade. */
	for ( int32_t i = 0; i < s.joint_count; ++i )
	{
		cr_assert_lt( fabs( s.y[i] ), skeleton_half_width( s.x[i], 10.0, 6.0, 0.0 ) + 1e-3, "joint %d inside", i );
		if ( s.vein[i] > 0 && s.vein[s.parent[i]] == 0 )
		{
			cr_expect_float_eq( s.y[s.parent[i]], 0.0f, 1e-6f, "attached to the midvein" );
		}
	}
	sere_skeleton_destroy( &s );
	p.mid_segments = 20;
	p.secondary_count = 2;
	p.secondary_segments = 4;
	skeleton_generated( &s, &p );
	cr_expect_eq( s.joint_count, 1 + 20 + 2 * 4 );
	sere_skeleton_destroy( &s );
}

/* ------------------------------------------------------------------------------------------- */

static void expect_grid_matches_brute_force( const float* jx, const float* jy, const float* jz, int32_t joints,
											 const float* x, const float* y, const float* z, int32_t n )
{
	sere_joint_grid* grid;
	cr_assert_eq( sere_joint_grid_create( jx, jy, jz, joints, &grid ), SERE_OK );
	int32_t* fast = malloc( (size_t) n * sizeof( int32_t ) );
	int32_t* slow = malloc( (size_t) n * sizeof( int32_t ) );
	cr_assert_eq( sere_joint_grid_band( grid, NULL, NULL, NULL, x, y, z, n, fast, NULL, NULL, NULL ), SERE_OK );
	sere_skeleton_ref_band( jx, jy, jz, joints, x, y, z, n, slow );
	for ( int32_t i = 0; i < n; ++i )
	{
		cr_assert_eq( fast[i], slow[i], "vertex %d (%g %g %g)", i, x[i], y[i], z[i] );
	}
	sere_joint_grid_destroy( grid );
	free( fast );
	free( slow );
}

/* A 3-D cloud of j joints in [0, 4] × [0, 2] × [0, 1] (denser near z = 0) and n queries in a box
 * three times as wide around it, from seed. */
static void joint_cloud( uint64_t seed, float* jx, float* jy, float* jz, int j, float* x, float* y, float* z, int n )
{
	for ( int i = 0; i < j; ++i )
	{
		jx[i] = (float) ( 4.0 * sere_test_unit( &seed ) );
		jy[i] = (float) ( 2.0 * sere_test_unit( &seed ) );
		jz[i] = (float) ( sere_test_unit( &seed ) * sere_test_unit( &seed ) );
	}
	for ( int i = 0; i < n; ++i )
	{
		x[i] = (float) ( 12.0 * sere_test_unit( &seed ) - 4.0 );
		y[i] = (float) ( 6.0 * sere_test_unit( &seed ) - 2.0 );
		z[i] = (float) ( 3.0 * sere_test_unit( &seed ) - 1.0 );
	}
}

Test( skeleton, banding_equals_brute_force )
{
	/* A generated leaf skeleton (planar) and a grid leaf mesh, as Sec. 5.2 uses them. */
	sere_skeleton s;
	skeleton_generated( &s, NULL );
	sere_tri_mesh m;
	skeleton_grid_leaf( &m, 10.0, 6.0, 0.0, 60, 40 );
	expect_grid_matches_brute_force( s.x, s.y, s.z, s.joint_count, m.x, m.y, m.z, m.vertex_count );

	/* A 3-D cloud of joints, queries inside and far outside its box. */
	enum
	{
		J = 700,
		N = 20000
	};
	static float jx[J], jy[J], jz[J], x[N], y[N], z[N];
	joint_cloud( 11, jx, jy, jz, J, x, y, z, N );
	expect_grid_matches_brute_force( jx, jy, jz, J, x, y, z, N );

	/* Exact ties: joints on an integer lattice (listed in a scrambled order) and queries on
	 * half-integers, equidistant from two, four or eight joints; the lower index must win. */
	int k = 0;
	for ( int i = 0; i < 6; ++i )
	{
		for ( int j = 0; j < 5; ++j )
		{
			for ( int l = 0; l < 3; ++l )
			{
				int slot = ( k * 37 ) % 90;
				jx[slot] = (float) i;
				jy[slot] = (float) j;
				jz[slot] = (float) l;
				++k;
			}
		}
	}
	int q = 0;
	for ( int i = -2; i < 14; ++i )
	{
		for ( int j = -2; j < 12; ++j )
		{
			for ( int l = -1; l < 6; ++l )
			{
				x[q] = 0.5f * (float) i;
				y[q] = 0.5f * (float) j;
				z[q++] = 0.5f * (float) l;
			}
		}
	}
	expect_grid_matches_brute_force( jx, jy, jz, 90, x, y, z, q );

	/* Degenerate joint sets: all in one point, all on a line, a single joint. */
	for ( int i = 0; i < 7; ++i )
	{
		jx[i] = 1.0f;
		jy[i] = 2.0f;
		jz[i] = 3.0f;
	}
	expect_grid_matches_brute_force( jx, jy, jz, 7, x, y, z, 2000 );
	for ( int i = 0; i < 50; ++i )
	{
		jx[i] = 0.1f * (float) ( ( i * 7 ) % 50 );
		jy[i] = jz[i] = 0.0f;
	}
	expect_grid_matches_brute_force( jx, jy, jz, 50, x, y, z, q );
	expect_grid_matches_brute_force( jx, jy, jz, 1, x, y, z, 2000 );
	sere_tri_mesh_destroy( &m );
	sere_skeleton_destroy( &s );
}

Test( skeleton, banding_rejects_bad_input )
{
	float j[3] = { 0, 1, NAN };
	sere_joint_grid* grid;
	cr_expect_eq( sere_joint_grid_create( j, j, j, 3, &grid ), SERE_ERR_NONFINITE );
	cr_expect_null( grid );
	cr_expect_eq( sere_joint_grid_create( j, j, j, 0, &grid ), SERE_ERR_ARGUMENT );
	cr_assert_eq( sere_joint_grid_create( j, j, j, 2, &grid ), SERE_OK );
	int32_t out[3];
	cr_expect_eq( sere_joint_grid_band( grid, NULL, NULL, NULL, j, j, j, 3, out, NULL, NULL, NULL ),
				  SERE_ERR_NONFINITE );
	sere_joint_grid_destroy( grid );
}

/* Records the banding of n queries on `threads` threads, then replays it on 1 to 3 (the record
 * does not depend on the threads) and checks what each pass found, left and counted. */
static void expect_band_floor( sere_joint_grid* grid, const float* x, const float* y, const float* z, int32_t n,
							   int32_t threads, sere_joint_grid_traffic* recorded )
{
	int32_t* plain = malloc( (size_t) n * sizeof( int32_t ) );
	int32_t* out = malloc( (size_t) n * sizeof( int32_t ) );
	cr_assert_eq( sere_joint_grid_set_threads( grid, threads ), SERE_OK );
	cr_assert_eq( sere_joint_grid_band( grid, NULL, NULL, NULL, x, y, z, n, plain, NULL, NULL, NULL ), SERE_OK );
	memset( out, 0xff, (size_t) n * sizeof( int32_t ) );
	cr_assert_eq( sere_joint_grid_record_band( grid, x, y, z, n, out, recorded ), SERE_OK );
	cr_assert( memcmp( out, plain, (size_t) n * sizeof( int32_t ) ) == 0, "recording changed what the search finds" );
	for ( int32_t replay = 1; replay <= 3; ++replay )
	{
		cr_assert_eq( sere_joint_grid_set_threads( grid, replay ), SERE_OK );
		sere_joint_grid_traffic replayed;
		memset( &replayed, 0xff, sizeof( replayed ) );
		cr_assert_eq( sere_joint_grid_touch_band( grid, x, y, z, n, out, &replayed ), SERE_OK );
		cr_assert( memcmp( out, plain, (size_t) n * sizeof( int32_t ) ) == 0,
				   "recorded on %d threads, replayed on %d: the floor changed a joint", threads, replay );
		cr_assert_eq( replayed.listed, recorded->listed );
		cr_assert_eq( replayed.cells, recorded->cells, "recorded on %d threads, replayed on %d: %ld cells of %ld",
					  threads, replay, (long) replayed.cells, (long) recorded->cells );
		cr_assert_eq( replayed.joints, recorded->joints, "recorded on %d threads, replayed on %d: %ld joints of %ld",
					  threads, replay, (long) replayed.joints, (long) recorded->joints );
	}
	free( plain );
	free( out );
}

Test( skeleton, band_floor_replays_the_recorded_search )
{
	/* A 3-D cloud of joints, queries inside its box (candidate lists) and far outside (rings). */
	enum
	{
		J = 700,
		N = 20000
	};
	static float jx[J], jy[J], jz[J], x[N], y[N], z[N];
	joint_cloud( 23, jx, jy, jz, J, x, y, z, N );
	sere_joint_grid* grid;
	cr_assert_eq( sere_joint_grid_create( jx, jy, jz, J, &grid ), SERE_OK );
	sere_joint_grid_traffic traffic;
	for ( int32_t threads = 1; threads <= 3; ++threads )
	{
		expect_band_floor( grid, x, y, z, N, threads, &traffic );
		cr_assert( traffic.listed > 0 && traffic.listed < N, "both paths: %ld of %d listed", (long) traffic.listed, N );
		/* a ring search opens at least its query's cell, and finds at least one joint */
		cr_assert_geq( traffic.cells, N - traffic.listed );
		cr_assert_geq( traffic.joints, N );
	}
	sere_joint_grid_destroy( grid );

	/* One joint, one cell: a query inside reads its list (the joint), one outside opens the cell
	 * (the joint) and stops, the grid being covered. */
	cr_assert_eq( sere_joint_grid_create( jx, jy, jz, 1, &grid ), SERE_OK );
	expect_band_floor( grid, x, y, z, N, 2, &traffic );
	cr_assert( traffic.listed > 0 && traffic.listed < N );
	cr_assert_eq( traffic.cells, N - traffic.listed );
	cr_assert_eq( traffic.joints, N );
	sere_joint_grid_destroy( grid );
}

Test( skeleton, band_floor_rejects_what_it_cannot_replay )
{
	float j[4] = { 0, 1, 2, 3 };
	int32_t out[4];
	sere_joint_grid* grid;
	cr_assert_eq( sere_joint_grid_create( j, j, j, 4, &grid ), SERE_OK );
	cr_expect_eq( sere_joint_grid_touch_band( grid, j, j, j, 4, out, NULL ), SERE_ERR_ARGUMENT, "no record yet" );
	cr_expect_eq( sere_joint_grid_record_band( NULL, j, j, j, 4, out, NULL ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_joint_grid_record_band( grid, j, j, j, -1, out, NULL ), SERE_ERR_ARGUMENT );
	cr_assert_eq( sere_joint_grid_record_band( grid, j, j, j, 4, out, NULL ), SERE_OK );
	cr_expect_eq( sere_joint_grid_touch_band( grid, j, j, j, 3, out, NULL ), SERE_ERR_ARGUMENT, "another count" );
	cr_expect_eq( sere_joint_grid_touch_band( NULL, j, j, j, 4, out, NULL ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_joint_grid_touch_band( grid, j, NULL, j, 4, out, NULL ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_joint_grid_touch_band( grid, j, j, j, 4, NULL, NULL ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_joint_grid_touch_band( grid, j, j, j, 4, out, NULL ), SERE_OK );
	j[2] = NAN;
	cr_expect_eq( sere_joint_grid_touch_band( grid, j, j, j, 4, out, NULL ), SERE_ERR_NONFINITE );
	cr_expect_eq( sere_joint_grid_record_band( grid, j, j, j, 4, out, NULL ), SERE_ERR_NONFINITE );
	j[2] = 2;
	cr_expect_eq( sere_joint_grid_touch_band( grid, j, j, j, 4, out, NULL ), SERE_OK, "a failed record keeps the old" );
	sere_joint_grid_destroy( grid );
}
