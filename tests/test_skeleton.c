/* Tests of the venation skeleton kernels (seed 003: Lu, Zhao, Guo 2009): subdivision, leaf and
 * venation skeletons, banding against brute force, forward kinematics with its limits, skinning
 * against the reference, piercing, the plant, determinism. */
#include "mesh/subdivide.h"
#include "ref/skeleton_ref.h"
#include "wilt/skeleton.h"

#include <criterion/criterion.h>
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#define DEG ( 3.14159265358979323846 / 180.0 )

static double unit_random( uint64_t* state )
{
	/* splitmix64, fixed seeds: every run sees the same points */
	uint64_t z = ( *state += 0x9e3779b97f4a7c15ull );
	z = ( z ^ ( z >> 30 ) ) * 0xbf58476d1ce4e5b9ull;
	z = ( z ^ ( z >> 27 ) ) * 0x94d049bb133111ebull;
	z ^= z >> 31;
	return (double) ( z >> 11 ) * ( 1.0 / 9007199254740992.0 );
}

/* Half-width of the parametric blade (sere_leaf_skeleton_generate) at x, with optional lobes
 * that make the outline concave. */
static double half_width( double x, double length, double width, double lobes )
{
	double xi = x / length;
	if ( xi <= 0.0 || xi >= 1.0 )
	{
		return 0.0;
	}
	double h = 0.5 * width * sqrt( xi ) * ( 1.0 - xi ) / ( sqrt( 1.0 / 3.0 ) * ( 2.0 / 3.0 ) );
	return h * ( 1.0 - lobes * fabs( sin( 3.0 * 3.14159265358979323846 * xi ) ) );
}

/* A planar leaf mesh without the triangulator: a grid over the blade's box, cut into triangles,
 * keeping those whose centroid is inside the blade (all of them when lobes < 0: a rectangle);
 * unused vertices are dropped. */
static void grid_leaf( sere_tri_mesh* mesh, double length, double width, double lobes, int32_t nx, int32_t ny )
{
	int32_t nv = ( nx + 1 ) * ( ny + 1 );
	int32_t* tri = malloc( 6 * (size_t) nx * ny * sizeof( int32_t ) );
	int32_t* used = calloc( (size_t) nv, sizeof( int32_t ) );
	int32_t count = 0;
	for ( int32_t j = 0; j < ny; ++j )
	{
		for ( int32_t i = 0; i < nx; ++i )
		{
			int32_t a = j * ( nx + 1 ) + i, b = a + 1, c = a + nx + 1, d = c + 1;
			int32_t cand[2][3] = { { a, b, d }, { a, d, c } };
			for ( int k = 0; k < 2; ++k )
			{
				double cx = 0.0, cy = 0.0;
				for ( int q = 0; q < 3; ++q )
				{
					cx += ( cand[k][q] % ( nx + 1 ) ) * length / nx / 3.0;
					cy += ( -0.5 * width + ( cand[k][q] / ( nx + 1 ) ) * width / ny ) / 3.0;
				}
				if ( lobes < 0.0 || fabs( cy ) < half_width( cx, length, width, lobes ) )
				{
					memcpy( tri + 3 * count++, cand[k], 3 * sizeof( int32_t ) );
				}
			}
		}
	}
	int32_t vertices = 0;
	for ( int32_t k = 0; k < 3 * count; ++k )
	{
		used[tri[k]] = 1;
	}
	for ( int32_t v = 0; v < nv; ++v )
	{
		used[v] = used[v] ? vertices++ : -1;
	}
	cr_assert_eq( sere_tri_mesh_create( mesh, vertices, count ), SERE_OK );
	for ( int32_t v = 0; v < nv; ++v )
	{
		if ( used[v] >= 0 )
		{
			int32_t i = v % ( nx + 1 ), j = v / ( nx + 1 );
			mesh->x[used[v]] = (float) ( i * length / nx );
			mesh->y[used[v]] = (float) ( -0.5 * width + j * width / ny );
			mesh->u[used[v]] = (float) i / nx;
			mesh->v[used[v]] = (float) j / ny;
		}
	}
	for ( int32_t k = 0; k < 3 * count; ++k )
	{
		mesh->tri[k] = used[tri[k]];
	}
	free( tri );
	free( used );
}

static void parametric_leaf( double* l, double* r, double* m, sere_leaf_skeleton* leaf )
{
	cr_assert_eq( sere_leaf_skeleton_generate( 10.0, 6.0, 9, l, r, m ), SERE_OK );
	*leaf = ( sere_leaf_skeleton ){ 9, 9, 9, l, r, m };
}

static void generated_skeleton( sere_skeleton* s, const sere_venation_params* params )
{
	double l[18], r[18], m[18];
	sere_leaf_skeleton leaf;
	parametric_leaf( l, r, m, &leaf );
	sere_venation_params p = params != NULL ? *params : sere_venation_params_default();
	sere_skeleton_check check;
	cr_assert_eq( sere_skeleton_generate( &leaf, &p, s, &check ), SERE_OK, "%s",
				  sere_skeleton_problem_text( check.problem ) );
}

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
	grid_leaf( &in, 10.0, 6.0, 0.0, 20, 12 );
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
	grid_leaf( &in, 10.0, 6.0, 0.3, 16, 12 );
	/* Jitter the vertices so edge lengths spread around the threshold. */
	uint64_t seed = 5;
	for ( int32_t i = 0; i < in.vertex_count; ++i )
	{
		in.x[i] += (float) ( 0.15 * ( unit_random( &seed ) - 0.5 ) );
		in.y[i] += (float) ( 0.15 * ( unit_random( &seed ) - 0.5 ) );
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
	grid_leaf( &in, 10.0, 6.0, 0.0, 4, 4 );
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
	parametric_leaf( l, r, m, &leaf );
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
	parametric_leaf( l, r, m, &leaf );
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
	generated_skeleton( &s, &p );
	cr_expect_eq( s.joint_count, 1 + 30 + 4 * 10 );
	cr_expect_eq( s.vein_count, 5 );
	/* Secondary veins start on midvein joints and stay inside the blade. */
	for ( int32_t i = 0; i < s.joint_count; ++i )
	{
		cr_assert_lt( fabs( s.y[i] ), half_width( s.x[i], 10.0, 6.0, 0.0 ) + 1e-3, "joint %d inside", i );
		if ( s.vein[i] > 0 && s.vein[s.parent[i]] == 0 )
		{
			cr_expect_float_eq( s.y[s.parent[i]], 0.0f, 1e-6f, "attached to the midvein" );
		}
	}
	sere_skeleton_destroy( &s );
	p.mid_segments = 20;
	p.secondary_count = 2;
	p.secondary_segments = 4;
	generated_skeleton( &s, &p );
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

Test( skeleton, banding_equals_brute_force )
{
	/* A generated leaf skeleton (planar) and a grid leaf mesh, as Sec. 5.2 uses them. */
	sere_skeleton s;
	generated_skeleton( &s, NULL );
	sere_tri_mesh m;
	grid_leaf( &m, 10.0, 6.0, 0.0, 60, 40 );
	expect_grid_matches_brute_force( s.x, s.y, s.z, s.joint_count, m.x, m.y, m.z, m.vertex_count );

	/* A 3-D cloud of joints, queries inside and far outside its box. */
	enum
	{
		J = 700,
		N = 20000
	};
	static float jx[J], jy[J], jz[J], x[N], y[N], z[N];
	uint64_t seed = 11;
	for ( int i = 0; i < J; ++i )
	{
		jx[i] = (float) ( 4.0 * unit_random( &seed ) );
		jy[i] = (float) ( 2.0 * unit_random( &seed ) );
		jz[i] = (float) ( unit_random( &seed ) * unit_random( &seed ) );
	}
	for ( int i = 0; i < N; ++i )
	{
		x[i] = (float) ( 12.0 * unit_random( &seed ) - 4.0 );
		y[i] = (float) ( 6.0 * unit_random( &seed ) - 2.0 );
		z[i] = (float) ( 3.0 * unit_random( &seed ) - 1.0 );
	}
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

/* ------------------------------------------------------------------------------------------- */

static sere_wilt_params no_limits( void )
{
	sere_wilt_params p = sere_wilt_params_default();
	p.droop_max = INFINITY;
	p.min_angle = 0.0f;
	return p;
}

/* Rest length of the segment parent → i and its posed length. */
static void segment_lengths( const sere_skeleton* s, const sere_joint_frames* f, int32_t i, double* rest,
							 double* posed )
{
	int32_t p = s->parent[i];
	*rest = sqrt( pow( (double) s->x[i] - s->x[p], 2 ) + pow( (double) s->y[i] - s->y[p], 2 ) +
				  pow( (double) s->z[i] - s->z[p], 2 ) );
	*posed = sqrt( pow( (double) f->x[i] - f->x[p], 2 ) + pow( (double) f->y[i] - f->y[p], 2 ) +
				   pow( (double) f->z[i] - f->z[p], 2 ) );
}

Test( skeleton, rotations_keep_segment_lengths_and_match_the_reference )
{
	sere_venation_params vp = sere_venation_params_default();
	vp.mid_bend = (float) ( 150.0 * DEG );
	vp.secondary_bend = (float) ( 120.0 * DEG );
	sere_skeleton s;
	generated_skeleton( &s, &vp );
	sere_joint_frames f;
	cr_assert_eq( sere_joint_frames_create( &f, s.joint_count ), SERE_OK );
	double* rx = malloc( (size_t) s.joint_count * 3 * sizeof( double ) );
	double *ry = rx + s.joint_count, *rz = ry + s.joint_count;
	sere_wilt_params limited = sere_wilt_params_default();
	limited.droop_max = 2.0f;
	sere_wilt_params free_params = no_limits();
	const sere_wilt_params* modes[2] = { &free_params, &limited };
	float ts[5] = { 0.0f, 0.3f, 0.6f, 0.9f, 1.0f };
	for ( int mode = 0; mode < 2; ++mode )
	{
		for ( int k = 0; k < 5; ++k )
		{
			sere_pose_stats stats;
			cr_assert_eq( sere_skeleton_pose( &s, 0, s.joint_count, ts[k], modes[mode], &f, &stats ), SERE_OK );
			for ( int32_t i = 1; i < s.joint_count; ++i )
			{
				double rest, posed;
				segment_lengths( &s, &f, i, &rest, &posed );
				/* Positions are stored in float (about 6e-8 relative to a coordinate of 10);
				 * over a segment of 0.5 that is 1e-6 relative, so 1e-5. */
				cr_assert_float_eq( posed, rest, 1e-5 * rest, "mode %d t %g joint %d", mode, ts[k], i );
				/* R Rᵀ = I: each rotation is orthonormal up to float storage (1e-5). */
				for ( int a = 0; a < 3; ++a )
				{
					for ( int b = 0; b < 3; ++b )
					{
						double dot = 0.0;
						for ( int c = 0; c < 3; ++c )
						{
							dot += (double) f.m[3 * a + c][i] * f.m[3 * b + c][i];
						}
						cr_assert_float_eq( dot, a == b ? 1.0 : 0.0, 1e-5 );
					}
				}
			}
			if ( ts[k] == 0.0f )
			{
				cr_expect_eq( stats.turning, 0 );
				for ( int32_t i = 0; i < s.joint_count; ++i )
				{
					cr_assert_eq( f.x[i], s.x[i], "t = 0 is the rest pose" );
					cr_assert_eq( f.z[i], s.z[i] );
				}
			}
			if ( mode == 0 )
			{
				sere_skeleton_ref_pose( &s, ts[k], free_params.spread, rx, ry, rz );
				for ( int32_t i = 0; i < s.joint_count; ++i )
				{
					/* Two routes to the same rotations (accumulated frames vs. rotating every
					 * descendant in turn), both in double, the kernel's stored in float: 1e-5 of
					 * the leaf length 10. */
					cr_assert_float_eq( f.x[i], rx[i], 1e-4, "joint %d", i );
					cr_assert_float_eq( f.y[i], ry[i], 1e-4, "joint %d", i );
					cr_assert_float_eq( f.z[i], rz[i], 1e-4, "joint %d", i );
				}
			}
		}
	}
	free( rx );
	sere_joint_frames_destroy( &f );
	sere_skeleton_destroy( &s );
}

Test( skeleton, wilting_turns_down_tips_first_and_not_past_straight_down )
{
	double mid[] = { 0, 0, 10, 0 };
	sere_vein_spec vein = { -1, 10, (float) ( 3.14159265358979323846 ), 2, mid };
	sere_skeleton s;
	cr_assert_eq( sere_skeleton_create( &vein, 1, &s, NULL ), SERE_OK );
	sere_joint_frames f;
	cr_assert_eq( sere_joint_frames_create( &f, s.joint_count ), SERE_OK );
	sere_wilt_params p = no_limits();
	p.spread = 0.5f;
	int32_t tip = s.joint_count - 1;
	float previous = 0.0f;
	for ( int k = 1; k <= 20; ++k )
	{
		sere_pose_stats stats;
		cr_assert_eq( sere_skeleton_pose( &s, 0, s.joint_count, k / 20.0f, &p, &f, &stats ), SERE_OK );
		/* The tip sinks monotonically; only gravity's plane is used (y stays 0). */
		cr_assert_leq( f.z[tip], previous + 1e-6f );
		previous = f.z[tip];
		for ( int32_t i = 0; i < s.joint_count; ++i )
		{
			cr_assert_float_eq( f.y[i], 0.0f, 1e-6f );
		}
		if ( k == 5 )
		{
			/* At t = 0.25 only joints with delay < 0.5 (the outer half) have started. */
			cr_expect_eq( f.z[4], 0.0f );
			cr_expect_lt( f.z[tip], f.z[7] );
		}
	}
	/* Total bend π over a horizontal vein: the segments reach straight down and stop there. */
	for ( int32_t i = 1; i < s.joint_count; ++i )
	{
		int32_t q = s.parent[i];
		double dz = (double) f.z[i] - f.z[q], dx = (double) f.x[i] - f.x[q];
		cr_assert_lt( atan2( -dz, dx ), 90.0 * DEG + 1e-5, "joint %d not past down", i );
	}
	double dz = (double) f.z[tip] - f.z[tip - 1], dx = (double) f.x[tip] - f.x[tip - 1];
	cr_expect_float_eq( atan2( -dz, dx ), 90.0 * DEG, 1e-5, "the tip segment hangs straight down" );
	sere_joint_frames_destroy( &f );
	sere_skeleton_destroy( &s );
}

/* The lowest a joint sinks below its rest height over the whole skeleton. */
static double deepest_droop( const sere_skeleton* s, const sere_joint_frames* f )
{
	double deepest = 0.0;
	for ( int32_t i = 0; i < s->joint_count; ++i )
	{
		deepest = fmax( deepest, (double) s->z[i] - f->z[i] );
	}
	return deepest;
}

/* The smallest included angle between adjacent segments of one vein. */
static double smallest_included_angle( const sere_skeleton* s, const sere_joint_frames* f )
{
	double smallest = 3.14159265358979323846;
	for ( int32_t i = 0; i < s->joint_count; ++i )
	{
		int32_t p = s->parent[i];
		if ( p < 0 || s->parent[p] < 0 || s->vein[p] != s->vein[i] )
		{
			continue;
		}
		int32_t g = s->parent[p];
		double a[3] = { (double) f->x[g] - f->x[p], (double) f->y[g] - f->y[p], (double) f->z[g] - f->z[p] };
		double b[3] = { (double) f->x[i] - f->x[p], (double) f->y[i] - f->y[p], (double) f->z[i] - f->z[p] };
		double dot = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
		double la = sqrt( a[0] * a[0] + a[1] * a[1] + a[2] * a[2] ),
			   lb = sqrt( b[0] * b[0] + b[1] * b[1] + b[2] * b[2] );
		smallest = fmin( smallest, acos( fmax( -1.0, fmin( 1.0, dot / ( la * lb ) ) ) ) );
	}
	return smallest;
}

Test( skeleton, droop_limit_holds )
{
	sere_venation_params vp = sere_venation_params_default();
	vp.mid_bend = (float) ( 170.0 * DEG );
	vp.secondary_bend = (float) ( 150.0 * DEG );
	sere_skeleton s;
	generated_skeleton( &s, &vp );
	sere_joint_frames f;
	cr_assert_eq( sere_joint_frames_create( &f, s.joint_count ), SERE_OK );
	sere_wilt_params p = no_limits();
	cr_assert_eq( sere_skeleton_pose( &s, 0, s.joint_count, 1.0f, &p, &f, NULL ), SERE_OK );
	double unlimited = deepest_droop( &s, &f );
	cr_assert_gt( unlimited, 3.0, "without the limit the tip sinks far" );
	float limits[3] = { 0.5f, 1.5f, 3.0f };
	for ( int k = 0; k < 3; ++k )
	{
		p.droop_max = limits[k];
		for ( int step = 1; step <= 10; ++step )
		{
			sere_pose_stats stats;
			cr_assert_eq( sere_skeleton_pose( &s, 0, s.joint_count, step / 10.0f, &p, &f, &stats ), SERE_OK );
			/* The limit is met exactly at the crossing in double; float storage of z (about
			 * 1e-6 here) is the tolerance. */
			cr_assert_leq( deepest_droop( &s, &f ), limits[k] + 1e-5, "limit %g t %g", limits[k], step / 10.0 );
			if ( step == 10 )
			{
				cr_expect_gt( stats.droop_limited, 0 );
				/* The limit is reached, not merely respected from afar. */
				cr_expect_gt( deepest_droop( &s, &f ), limits[k] - 1e-3 );
			}
		}
	}
	sere_joint_frames_destroy( &f );
	sere_skeleton_destroy( &s );
}

Test( skeleton, minimal_angle_limit_holds )
{
	/* Few joints and a strong bend: 4 segments turning 160° in all, 40° each. */
	double mid[] = { 0, 0, 10, 0 };
	double side[] = { 5, 0, 7, 4 };
	sere_vein_spec veins[2] = { { -1, 4, (float) ( 160.0 * DEG ), 2, mid },
								{ 0, 3, (float) ( 150.0 * DEG ), 2, side } };
	sere_skeleton s;
	cr_assert_eq( sere_skeleton_create( veins, 2, &s, NULL ), SERE_OK );
	sere_joint_frames f;
	cr_assert_eq( sere_joint_frames_create( &f, s.joint_count ), SERE_OK );
	sere_wilt_params p = no_limits();
	p.spread = 0.0f;
	cr_assert_eq( sere_skeleton_pose( &s, 0, s.joint_count, 1.0f, &p, &f, NULL ), SERE_OK );
	cr_assert_lt( smallest_included_angle( &s, &f ), 145.0 * DEG, "without the limit the vein kinks" );
	p.min_angle = (float) ( 150.0 * DEG );
	for ( int step = 1; step <= 10; ++step )
	{
		sere_pose_stats stats;
		cr_assert_eq( sere_skeleton_pose( &s, 0, s.joint_count, step / 10.0f, &p, &f, &stats ), SERE_OK );
		/* Angles from float positions over segments of 2.5: about 1e-6 rad; 1e-4 is safe. */
		cr_assert_geq( smallest_included_angle( &s, &f ), 150.0 * DEG - 1e-4, "t %g", step / 10.0 );
		if ( step == 10 )
		{
			cr_expect_gt( stats.angle_limited, 0 );
		}
	}
	sere_joint_frames_destroy( &f );
	sere_skeleton_destroy( &s );
}

Test( skeleton, pose_rejects_bad_input )
{
	sere_skeleton s;
	generated_skeleton( &s, NULL );
	sere_joint_frames f;
	cr_assert_eq( sere_joint_frames_create( &f, s.joint_count ), SERE_OK );
	sere_wilt_params p = sere_wilt_params_default();
	cr_expect_eq( sere_skeleton_pose( &s, 0, s.joint_count, NAN, &p, &f, NULL ), SERE_ERR_NONFINITE );
	cr_expect_eq( sere_skeleton_pose( &s, 1, s.joint_count - 1, 0.5f, &p, &f, NULL ), SERE_ERR_ARGUMENT,
				  "a range must be a whole tree" );
	p.spread = 1.0f;
	cr_expect_eq( sere_skeleton_pose( &s, 0, s.joint_count, 0.5f, &p, &f, NULL ), SERE_ERR_ARGUMENT );
	p = sere_wilt_params_default();
	p.droop_max = -1.0f;
	cr_expect_eq( sere_skeleton_pose( &s, 0, s.joint_count, 0.5f, &p, &f, NULL ), SERE_ERR_ARGUMENT );
	p.droop_max = NAN;
	cr_expect_eq( sere_skeleton_pose( &s, 0, s.joint_count, 0.5f, &p, &f, NULL ), SERE_ERR_NONFINITE );
	sere_joint_frames_destroy( &f );
	sere_skeleton_destroy( &s );
}

/* ------------------------------------------------------------------------------------------- */

Test( skeleton, skinning_equals_reference_bitwise )
{
	sere_skeleton s;
	generated_skeleton( &s, NULL );
	sere_joint_frames f;
	cr_assert_eq( sere_joint_frames_create( &f, s.joint_count ), SERE_OK );
	sere_wilt_params p = sere_wilt_params_default();
	cr_assert_eq( sere_skeleton_pose( &s, 0, s.joint_count, 0.8f, &p, &f, NULL ), SERE_OK );
	enum
	{
		N = 10007
	};
	static int32_t joint[N];
	static float ox[N], oy[N], oz[N], x[N], y[N], z[N], rx[N], ry[N], rz[N];
	uint64_t seed = 3;
	for ( int i = 0; i < N; ++i )
	{
		joint[i] = (int32_t) ( unit_random( &seed ) * s.joint_count );
		ox[i] = (float) ( unit_random( &seed ) - 0.5 );
		oy[i] = (float) ( unit_random( &seed ) - 0.5 );
		oz[i] = (float) ( 0.1 * ( unit_random( &seed ) - 0.5 ) );
	}
	sere_joint_frames_skin( &f, joint, ox, oy, oz, N, x, y, z, 0 );
	sere_skeleton_ref_skin( &f, joint, ox, oy, oz, N, rx, ry, rz );
	/* The same operations in the same order without contraction: identical bits. */
	cr_expect_eq( memcmp( x, rx, sizeof( x ) ), 0 );
	cr_expect_eq( memcmp( y, ry, sizeof( y ) ), 0 );
	cr_expect_eq( memcmp( z, rz, sizeof( z ) ), 0 );
	sere_joint_frames_destroy( &f );
	sere_skeleton_destroy( &s );
}

/* ------------------------------------------------------------------------------------------- */

static int64_t count_intersections( const int32_t* tri, int32_t triangles, int32_t vertices, const float* x,
									const float* y, const float* z )
{
	sere_bvh* bvh;
	cr_assert_eq( sere_bvh_create( tri, triangles, vertices, x, y, z, &bvh ), SERE_OK );
	int64_t count = sere_mesh_count_intersections( bvh, tri, triangles, x, y, z, 0 );
	sere_bvh_destroy( bvh );
	return count;
}

Test( skeleton, intersection_count )
{
	/* Two triangles through each other, then apart, then sharing a corner and folded through. */
	float x[6] = { 0, 2, 0, 0.5f, 0.5f, 0.5f };
	float y[6] = { 0, 0, 2, 0.5f, 0.5f, -1 };
	float z[6] = { 0, 0, 0, -1, 1, 0 };
	int32_t tri[6] = { 0, 1, 2, 3, 4, 5 };
	cr_expect_eq( count_intersections( tri, 2, 6, x, y, z ), 1 );
	z[3] = 0.5f;
	cr_expect_eq( count_intersections( tri, 2, 6, x, y, z ), 0 );
	/* Shared corner 0: the second triangle's far edge passes through the first. */
	int32_t shared[6] = { 0, 1, 2, 0, 3, 4 };
	x[3] = 1.0f, y[3] = 0.3f, z[3] = -1.0f;
	x[4] = 1.0f, y[4] = 0.3f, z[4] = 1.0f;
	cr_expect_eq( count_intersections( shared, 2, 6, x, y, z ), 1 );
	z[3] = 0.2f;
	cr_expect_eq( count_intersections( shared, 2, 6, x, y, z ), 0 );
	/* A planar mesh never counts, however many neighbours touch. */
	sere_tri_mesh m;
	grid_leaf( &m, 10.0, 6.0, 0.3, 30, 20 );
	cr_expect_eq( count_intersections( m.tri, m.triangle_count, m.vertex_count, m.x, m.y, m.z ), 0 );
	sere_tri_mesh_destroy( &m );
}

Test( skeleton, piercing_shortens_moves_through_the_mesh )
{
	/* A 10 × 10 sheet at z = 0 and a separate small flap above it, pushed partly through. */
	sere_tri_mesh sheet;
	grid_leaf( &sheet, 4.0, 4.0, -1.0, 10, 10 );
	int32_t n = sheet.vertex_count + 3, f = sheet.triangle_count + 1;
	float *x = calloc( (size_t) n, sizeof( float ) ), *y = calloc( (size_t) n, sizeof( float ) );
	float *z = calloc( (size_t) n, sizeof( float ) ), *tx = calloc( (size_t) n, sizeof( float ) );
	float *ty = calloc( (size_t) n, sizeof( float ) ), *tz = calloc( (size_t) n, sizeof( float ) );
	int32_t* tri = malloc( 3 * (size_t) f * sizeof( int32_t ) );
	memcpy( x, sheet.x, (size_t) sheet.vertex_count * sizeof( float ) );
	memcpy( y, sheet.y, (size_t) sheet.vertex_count * sizeof( float ) );
	memcpy( tri, sheet.tri, 3 * (size_t) sheet.triangle_count * sizeof( int32_t ) );
	int32_t a = sheet.vertex_count;
	float flap[3][2] = { { 1.1f, 0.3f }, { 2.3f, 0.4f }, { 1.5f, -0.9f } };
	for ( int k = 0; k < 3; ++k )
	{
		x[a + k] = flap[k][0];
		y[a + k] = flap[k][1];
		z[a + k] = 0.5f;
		tri[3 * sheet.triangle_count + k] = a + k;
	}
	memcpy( tx, x, (size_t) n * sizeof( float ) );
	memcpy( ty, y, (size_t) n * sizeof( float ) );
	/* Two corners of the flap are pushed through the sheet, the third stays above. */
	memcpy( tz, z, (size_t) n * sizeof( float ) );
	tz[a] = tz[a + 1] = -0.5f;
	cr_assert_gt( count_intersections( tri, f, n, tx, ty, tz ), 0, "the unchecked move goes through" );
	sere_pierce* pierce;
	cr_assert_eq( sere_pierce_create( tri, f, n, x, y, z, NULL, &pierce ), SERE_OK );
	sere_pierce_stats stats;
	cr_assert_eq( sere_pierce_step( pierce, x, y, z, tx, ty, tz, 0.01f, &stats ), SERE_OK );
	cr_expect_eq( stats.shortened, 2 );
	cr_expect_eq( stats.reverted, 0 );
	cr_expect_eq( tz[a + 2], 0.5f );
	for ( int k = 0; k < 2; ++k )
	{
		/* Stopped `margin` above the sheet; float rounding of 0.5 − 0.49: 1e-6. */
		cr_expect_float_eq( tz[a + k], 0.01f, 1e-6f );
		cr_expect_eq( tx[a + k], x[a + k], "straight down: x unchanged" );
	}
	cr_expect_eq( count_intersections( tri, f, n, tx, ty, tz ), 0 );
	cr_expect_eq( sere_mesh_count_intersections( sere_pierce_bvh( pierce ), tri, f, tx, ty, tz, 0 ), 0,
				  "the workspace BVH is refit to the result" );

	/* An edge swept through a triangle while both its ends pass outside: no vertex pierces, the
	 * pull-back has to undo it. One big triangle at z = 0, one flap whose far corner drops
	 * outside it. */
	float bx[6] = { -1, 3, -1, -3, 5, -3 }, by[6] = { -1, -1, 3, 0.5f, 0.5f, 2 }, bz[6] = { 0, 0, 0, 1, 1, 1 };
	float cx[6], cy[6], cz[6];
	memcpy( cx, bx, sizeof( bx ) );
	memcpy( cy, by, sizeof( by ) );
	memcpy( cz, bz, sizeof( bz ) );
	cz[4] = -1.0f;
	int32_t two[6] = { 0, 1, 2, 3, 4, 5 };
	cr_assert_eq( count_intersections( two, 2, 6, cx, cy, cz ), 1 );
	sere_pierce* small;
	cr_assert_eq( sere_pierce_create( two, 2, 6, bx, by, bz, NULL, &small ), SERE_OK );
	cr_assert_eq( sere_pierce_step( small, bx, by, bz, cx, cy, cz, 0.01f, &stats ), SERE_OK );
	cr_expect_eq( stats.shortened, 0 );
	cr_expect_gt( stats.pulled_back, 0 );
	cr_expect_eq( count_intersections( two, 2, 6, cx, cy, cz ), 0 );
	cr_expect_lt( cz[4], 1.0f, "the corner still moved part of the way" );
	sere_pierce_destroy( small );
	sere_pierce_destroy( pierce );
	free( x );
	free( y );
	free( z );
	free( tx );
	free( ty );
	free( tz );
	free( tri );
	sere_tri_mesh_destroy( &sheet );
}

/* ------------------------------------------------------------------------------------------- */

/* A small plant: `leaves` grid leaves, alternately placed up a stem, onsets from the bottom. */
static sere_plant* small_plant( sere_tri_mesh* mesh, sere_skeleton* s, int32_t leaves, double lobes )
{
	grid_leaf( mesh, 10.0, 6.0, lobes, 40, 24 );
	/* Four secondary veins that turn steeply: where the regions of two of them meet, rigid
	 * banding folds the blade, which gives the piercing check work to do. */
	sere_venation_params vp = sere_venation_params_default();
	vp.secondary_count = 4;
	vp.secondary_segments = 6;
	vp.angle = (float) ( 50.0 * DEG );
	vp.secondary_bend = (float) ( 60.0 * DEG );
	generated_skeleton( s, &vp );
	sere_leaf_template t = { mesh, s };
	sere_leaf_placement* l = calloc( (size_t) leaves, sizeof( sere_leaf_placement ) );
	for ( int32_t k = 0; k < leaves; ++k )
	{
		l[k].template_index = 0;
		l[k].base[2] = 4.0f * (float) k;
		l[k].azimuth = (float) ( k * 137.5 * DEG );
		l[k].elevation = (float) ( 35.0 * DEG );
		l[k].scale = 1.0f - 0.05f * (float) k;
		l[k].onset = 0.25f * (float) k;
	}
	sere_plant* plant;
	cr_assert_eq( sere_plant_create( &t, 1, l, leaves, &plant ), SERE_OK );
	free( l );
	return plant;
}

Test( skeleton, wilting_never_self_intersects )
{
	/* A plain and a lobed (concave) blade on a plant of three leaves: with the piercing check
	 * no frame intersects itself or another leaf. */
	for ( int lobed = 0; lobed < 2; ++lobed )
	{
		sere_tri_mesh mesh;
		sere_skeleton s;
		sere_plant* plant = small_plant( &mesh, &s, 3, lobed ? 0.3 : 0.0 );
		sere_wilt_params p = sere_wilt_params_default();
		sere_bvh* bvh;
		cr_assert_eq( sere_bvh_create( plant->tri, plant->triangle_count, plant->vertex_count, plant->x, plant->y,
									   plant->z, &bvh ),
					  SERE_OK );
		if ( !lobed )
		{
			/* Rigid banding alone folds the blade where two secondary veins' regions meet
			 * (the check has something to do here). */
			p.pierce = 0;
			int64_t unchecked = 0;
			for ( int frame = 1; frame <= 30; ++frame )
			{
				cr_assert_eq( sere_plant_frame( plant, frame / 20.0f, &p, NULL ), SERE_OK );
				cr_assert_eq( sere_bvh_refit( bvh, plant->x, plant->y, plant->z ), SERE_OK );
				unchecked += sere_mesh_count_intersections( bvh, plant->tri, plant->triangle_count, plant->x, plant->y,
															plant->z, 0 );
			}
			cr_assert_gt( unchecked, 0 );
			p.pierce = 1;
			sere_plant_reset( plant );
		}
		for ( int frame = 1; frame <= 30; ++frame )
		{
			sere_wilt_stats stats;
			cr_assert_eq( sere_plant_frame( plant, frame / 20.0f, &p, &stats ), SERE_OK );
			cr_assert_eq( sere_bvh_refit( bvh, plant->x, plant->y, plant->z ), SERE_OK );
			cr_assert_eq( sere_mesh_count_intersections( bvh, plant->tri, plant->triangle_count, plant->x, plant->y,
														 plant->z, 0 ),
						  0, "lobed %d frame %d", lobed, frame );
			cr_assert_eq( stats.pierce.reverted, 0 );
		}
		/* The plant did wilt: every leaf is at t = 1 and its tip far below its rest height. */
		for ( int32_t k = 0; k < plant->leaf_count; ++k )
		{
			cr_expect_eq( plant->leaf_t[k], 1.0f );
			int32_t tip = plant->joint_first[k] + 20; /* the midvein tip: joint 20 in depth-first order */
			cr_expect_lt( plant->frames.z[tip], plant->joints.z[tip] - 2.0f );
		}
		sere_bvh_destroy( bvh );
		sere_plant_destroy( plant );
		sere_tri_mesh_destroy( &mesh );
		sere_skeleton_destroy( &s );
	}
}

Test( skeleton, plant_keeps_texture_coordinates_and_starts_from_the_bottom )
{
	sere_tri_mesh mesh;
	sere_skeleton s;
	sere_plant* plant = small_plant( &mesh, &s, 4, 0.0 );
	size_t bytes = (size_t) plant->vertex_count * sizeof( float );
	float* u = malloc( bytes );
	float* v = malloc( bytes );
	memcpy( u, plant->u, bytes );
	memcpy( v, plant->v, bytes );
	sere_wilt_params p = sere_wilt_params_default();
	/* At time 0.5 leaves 0 and 1 (onsets 0 and 0.25) wilt, leaves 2 and 3 have not started. */
	for ( int frame = 1; frame <= 5; ++frame )
	{
		cr_assert_eq( sere_plant_frame( plant, frame * 0.1f, &p, NULL ), SERE_OK );
	}
	for ( int32_t k = 0; k < plant->leaf_count; ++k )
	{
		double moved = 0.0;
		for ( int32_t i = plant->vertex_first[k]; i < plant->vertex_first[k + 1]; ++i )
		{
			moved = fmax( moved, fabs( (double) plant->z[i] - plant->rz[i] ) );
		}
		if ( k < 2 )
		{
			cr_expect_gt( moved, 0.1, "leaf %d wilts", k );
		}
		else
		{
			cr_expect_eq( moved, 0.0, "leaf %d waits", k );
		}
	}
	cr_expect_gt( plant->leaf_t[0], plant->leaf_t[1] );
	/* Sec. 6: texture coordinates are computed before the deformation and never remapped. */
	for ( int frame = 6; frame <= 25; ++frame )
	{
		cr_assert_eq( sere_plant_frame( plant, frame * 0.1f, &p, NULL ), SERE_OK );
	}
	cr_expect_eq( memcmp( u, plant->u, bytes ), 0 );
	cr_expect_eq( memcmp( v, plant->v, bytes ), 0 );
	/* Back to rest exactly. */
	sere_plant_reset( plant );
	cr_expect_eq( memcmp( plant->x, plant->rx, bytes ), 0 );
	free( u );
	free( v );
	sere_plant_destroy( plant );
	sere_tri_mesh_destroy( &mesh );
	sere_skeleton_destroy( &s );
}

Test( skeleton, one_and_two_threads_identical )
{
	float* result[2][3];
	int32_t counts[2][2];
	for ( int run = 0; run < 2; ++run )
	{
		omp_set_num_threads( run + 1 );
		sere_tri_mesh mesh;
		sere_skeleton s;
		sere_plant* plant = small_plant( &mesh, &s, 5, 0.3 );
		sere_wilt_params p = sere_wilt_params_default();
		p.droop_max = 4.0f;
		sere_wilt_stats stats;
		counts[run][0] = counts[run][1] = 0;
		for ( int frame = 1; frame <= 30; ++frame )
		{
			cr_assert_eq( sere_plant_frame( plant, frame / 15.0f, &p, &stats ), SERE_OK );
			counts[run][0] += stats.pierce.shortened;
			counts[run][1] += stats.pierce.pulled_back;
		}
		size_t bytes = (size_t) plant->vertex_count * sizeof( float );
		float* xyz[3] = { plant->x, plant->y, plant->z };
		for ( int a = 0; a < 3; ++a )
		{
			result[run][a] = malloc( bytes );
			memcpy( result[run][a], xyz[a], bytes );
		}
		if ( run == 1 )
		{
			for ( int a = 0; a < 3; ++a )
			{
				cr_expect_eq( memcmp( result[0][a], result[1][a], bytes ), 0, "axis %d", a );
			}
		}
		sere_plant_destroy( plant );
		sere_tri_mesh_destroy( &mesh );
		sere_skeleton_destroy( &s );
	}
	cr_expect_eq( counts[0][0], counts[1][0] );
	cr_expect_eq( counts[0][1], counts[1][1] );
	for ( int run = 0; run < 2; ++run )
	{
		for ( int a = 0; a < 3; ++a )
		{
			free( result[run][a] );
		}
	}
	omp_set_num_threads( 2 );
}

Test( skeleton, plant_rejects_bad_input )
{
	sere_tri_mesh mesh;
	sere_skeleton s;
	grid_leaf( &mesh, 10.0, 6.0, 0.0, 10, 6 );
	generated_skeleton( &s, NULL );
	sere_leaf_template t = { &mesh, &s };
	sere_leaf_placement l = { 0, { 0, 0, 0 }, 0.0f, 0.5f, 1.0f, 0.0f };
	sere_plant* plant;
	l.template_index = 1;
	cr_expect_eq( sere_plant_create( &t, 1, &l, 1, &plant ), SERE_ERR_ARGUMENT );
	l.template_index = 0;
	l.scale = 0.0f;
	cr_expect_eq( sere_plant_create( &t, 1, &l, 1, &plant ), SERE_ERR_ARGUMENT );
	l.scale = 1.0f;
	l.base[1] = NAN;
	cr_expect_eq( sere_plant_create( &t, 1, &l, 1, &plant ), SERE_ERR_NONFINITE );
	l.base[1] = 0.0f;
	cr_assert_eq( sere_plant_create( &t, 1, &l, 1, &plant ), SERE_OK );
	sere_wilt_params p = sere_wilt_params_default();
	cr_expect_eq( sere_plant_frame( plant, INFINITY, &p, NULL ), SERE_ERR_NONFINITE );
	p.min_angle = 4.0f;
	cr_expect_eq( sere_plant_frame( plant, 0.5f, &p, NULL ), SERE_ERR_ARGUMENT );
	sere_plant_destroy( plant );
	sere_tri_mesh_destroy( &mesh );
	sere_skeleton_destroy( &s );
}
