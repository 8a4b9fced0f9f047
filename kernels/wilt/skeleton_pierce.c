/* sere — Piercing (Sec. 6) and the self-intersection count. Seed 003: Lu, Zhao, Guo 2009. */
/* _GNU_SOURCE: sched_getaffinity for core/internal/team.h. */
#define _GNU_SOURCE

#include "wilt/internal/skeleton_shared.h"

#include "core/array.h"
#include "core/internal/simd_fixed.h"
#include "core/internal/team.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* ---------------------------------------------------------------------------------------------
 * Piercing (Sec. 6) and the self-intersection count. */

/* Where segment p0 → p1 crosses triangle abc: the fraction along the segment, or −1. The
 * segment must change sides of the triangle's plane and cross it inside the closed triangle.
 * Coplanar segments never count (a planar rest mesh is not self-intersecting). */
static double segment_triangle( const double p0[3], const double p1[3], const double a[3], const double b[3],
								const double c[3] )
{
	double e1[3] = { b[0] - a[0], b[1] - a[1], b[2] - a[2] };
	double e2[3] = { c[0] - a[0], c[1] - a[1], c[2] - a[2] };
	double n[3] = { e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0] };
	double d0 = n[0] * ( p0[0] - a[0] ) + n[1] * ( p0[1] - a[1] ) + n[2] * ( p0[2] - a[2] );
	double d1 = n[0] * ( p1[0] - a[0] ) + n[1] * ( p1[1] - a[1] ) + n[2] * ( p1[2] - a[2] );
	if ( ( d0 >= 0.0 ) == ( d1 >= 0.0 ) || d0 == d1 )
	{
		return -1.0;
	}
	double s = d0 / ( d0 - d1 );
	double q[3] = { p0[0] + s * ( p1[0] - p0[0] ), p0[1] + s * ( p1[1] - p0[1] ), p0[2] + s * ( p1[2] - p0[2] ) };
	const double* corner[3] = { a, b, c };
	for ( int k = 0; k < 3; ++k )
	{
		const double* u = corner[k];
		const double* v = corner[( k + 1 ) % 3];
		double ex = v[0] - u[0], ey = v[1] - u[1], ez = v[2] - u[2];
		double wx = q[0] - u[0], wy = q[1] - u[1], wz = q[2] - u[2];
		double side = n[0] * ( ey * wz - ez * wy ) + n[1] * ( ez * wx - ex * wz ) + n[2] * ( ex * wy - ey * wx );
		if ( side < 0.0 )
		{
			return -1.0;
		}
	}
	return s;
}

static void corner( const float* x, const float* y, const float* z, int32_t i, double out[3] )
{
	out[0] = x[i];
	out[1] = y[i];
	out[2] = z[i];
}

/* Eight consecutive vertices share one walk down the tree (sere_bvh_query_group); vertices of a
 * plant are ordered by joint, so the eight boxes are close together. */
typedef struct pierce_group
{
	const int32_t* tri;
	const float *x, *y, *z; /* previous positions: the mesh a move must not pass through */
	int32_t first;			/* the vertex of lane 0 */
	double p0[SERE_BVH_WIDTH][3], p1[SERE_BVH_WIDTH][3];
	double hit[SERE_BVH_WIDTH]; /* smallest crossing fraction per lane */
} pierce_group;

static void pierce_visit( void* context, int32_t t, uint32_t lanes )
{
	pierce_group* g = context;
	const int32_t* c = g->tri + 3 * t;
	double a[3], b[3], d[3];
	corner( g->x, g->y, g->z, c[0], a );
	corner( g->x, g->y, g->z, c[1], b );
	corner( g->x, g->y, g->z, c[2], d );
	while ( lanes != 0 )
	{
		int k = __builtin_ctz( lanes );
		lanes &= lanes - 1;
		int32_t v = g->first + k;
		if ( c[0] == v || c[1] == v || c[2] == v )
		{
			continue;
		}
		double s = segment_triangle( g->p0[k], g->p1[k], a, b, d );
		if ( s >= 0.0 && s < g->hit[k] )
		{
			g->hit[k] = s;
		}
	}
}

static int32_t pierce_limit( const sere_bvh* bvh, const int32_t* tri, const float* px, const float* py, const float* pz,
							 float* x, float* y, float* z, int32_t vertex_count, float margin, uint8_t* modified,
							 int32_t threads )
{
	int32_t shortened = 0;
	int32_t groups = ( vertex_count + SERE_BVH_WIDTH - 1 ) / SERE_BVH_WIDTH;
#pragma omp parallel for num_threads( sere_team_for( threads ) ) schedule( dynamic, 32 ) reduction( + : shortened )
	for ( int32_t b = 0; b < groups; ++b )
	{
		pierce_group g;
		sere_bvh_group boxes;
		g.tri = tri;
		g.x = px;
		g.y = py;
		g.z = pz;
		g.first = b * SERE_BVH_WIDTH;
		boxes.count = vertex_count - g.first < SERE_BVH_WIDTH ? vertex_count - g.first : SERE_BVH_WIDTH;
		int moving = 0;
		for ( int k = 0; k < boxes.count; ++k )
		{
			int32_t i = g.first + k;
			g.hit[k] = INFINITY;
			corner( px, py, pz, i, g.p0[k] );
			corner( x, y, z, i, g.p1[k] );
			int still = x[i] == px[i] && y[i] == py[i] && z[i] == pz[i];
			moving |= !still;
			/* A vertex that does not move cannot pierce anything: a NaN box leaves its lane out.
			 * The bounds by single instructions (fminf and fmaxf are library calls): both positions
			 * are finite here (sere_pierce_step checks them first). */
			boxes.lo_x[k] = still ? NAN : sere_min_x86( px[i], x[i] );
			boxes.lo_y[k] = sere_min_x86( py[i], y[i] );
			boxes.lo_z[k] = sere_min_x86( pz[i], z[i] );
			boxes.hi_x[k] = sere_max_x86( px[i], x[i] );
			boxes.hi_y[k] = sere_max_x86( py[i], y[i] );
			boxes.hi_z[k] = sere_max_x86( pz[i], z[i] );
		}
		if ( !moving )
		{
			continue;
		}
		sere_bvh_query_group( bvh, &boxes, pierce_visit, &g );
		for ( int k = 0; k < boxes.count; ++k )
		{
			if ( g.hit[k] <= 1.0 )
			{
				int32_t i = g.first + k;
				double d[3] = { g.p1[k][0] - g.p0[k][0], g.p1[k][1] - g.p0[k][1], g.p1[k][2] - g.p0[k][2] };
				double length = sqrt( d[0] * d[0] + d[1] * d[1] + d[2] * d[2] );
				double s = g.hit[k] - margin / length;
				s = s > 0.0 ? s : 0.0;
				x[i] = (float) ( g.p0[k][0] + s * d[0] );
				y[i] = (float) ( g.p0[k][1] + s * d[1] );
				z[i] = (float) ( g.p0[k][2] + s * d[2] );
				modified[i] = 1;
				++shortened;
			}
		}
	}
	return shortened;
}

static int edge_hits( const float* x, const float* y, const float* z, const int32_t* from, int e0, int e1,
					  const int32_t* onto )
{
	double p0[3], p1[3], a[3], b[3], c[3];
	corner( x, y, z, from[e0], p0 );
	corner( x, y, z, from[e1], p1 );
	corner( x, y, z, onto[0], a );
	corner( x, y, z, onto[1], b );
	corner( x, y, z, onto[2], c );
	return segment_triangle( p0, p1, a, b, c ) >= 0.0;
}

/* The corners of `from` against the plane of `onto`, with exactly the arithmetic of
 * segment_triangle, so an edge whose ends do not change sides here fails its plane test there. */
static void plane_sides( const float* x, const float* y, const float* z, const int32_t* onto, const int32_t* from,
						 double d[3] )
{
	double a[3], b[3], c[3];
	corner( x, y, z, onto[0], a );
	corner( x, y, z, onto[1], b );
	corner( x, y, z, onto[2], c );
	double e1[3] = { b[0] - a[0], b[1] - a[1], b[2] - a[2] };
	double e2[3] = { c[0] - a[0], c[1] - a[1], c[2] - a[2] };
	double n[3] = { e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0] };
	for ( int k = 0; k < 3; ++k )
	{
		double p[3];
		corner( x, y, z, from[k], p );
		d[k] = n[0] * ( p[0] - a[0] ) + n[1] * ( p[1] - a[1] ) + n[2] * ( p[2] - a[2] );
	}
}

static int may_cross( const double d[3], int i, int j )
{
	return ( d[i] >= 0.0 ) != ( d[j] >= 0.0 ) && d[i] != d[j];
}

/* Triangles s and o intersect: sharing an edge they never count (only a coplanar fold could
 * make them); sharing one corner, only the edges opposite it can cross the other triangle
 * anywhere but at that corner; otherwise any of the six edges. An edge is tested only when its
 * ends lie on both sides of the other triangle's plane, which rejects most pairs cheaply. */
static int triangles_intersect( const float* x, const float* y, const float* z, const int32_t* s, const int32_t* o )
{
	int shared = 0, s_at = -1, o_at = -1;
	for ( int i = 0; i < 3; ++i )
	{
		for ( int j = 0; j < 3; ++j )
		{
			if ( s[i] == o[j] )
			{
				++shared;
				s_at = i;
				o_at = j;
			}
		}
	}
	if ( shared > 1 )
	{
		return 0;
	}
	double ds[3], dn[3];
	plane_sides( x, y, z, o, s, ds );
	plane_sides( x, y, z, s, o, dn );
	if ( shared == 1 )
	{
		int s1 = ( s_at + 1 ) % 3, s2 = ( s_at + 2 ) % 3, o1 = ( o_at + 1 ) % 3, o2 = ( o_at + 2 ) % 3;
		return ( may_cross( ds, s1, s2 ) && edge_hits( x, y, z, s, s1, s2, o ) ) ||
			   ( may_cross( dn, o1, o2 ) && edge_hits( x, y, z, o, o1, o2, s ) );
	}
	for ( int k = 0; k < 3; ++k )
	{
		int l = ( k + 1 ) % 3;
		if ( ( may_cross( ds, k, l ) && edge_hits( x, y, z, s, k, l, o ) ) ||
			 ( may_cross( dn, k, l ) && edge_hits( x, y, z, o, k, l, s ) ) )
		{
			return 1;
		}
	}
	return 0;
}

static void triangle_box( const float* x, const float* y, const float* z, const int32_t* c, float lo[3], float hi[3] )
{
	const float* p[3] = { x, y, z };
	for ( int a = 0; a < 3; ++a )
	{
		lo[a] = sere_min_x86( sere_min_x86( p[a][c[0]], p[a][c[1]] ), p[a][c[2]] );
		hi[a] = sere_max_x86( sere_max_x86( p[a][c[0]], p[a][c[1]] ), p[a][c[2]] );
	}
}

struct sere_pierce
{
	int32_t threads; /* sere_pierce_set_threads */
	int32_t vertex_count;
	int32_t triangle_count;
	int32_t* tri;
	int32_t* group;		/* rigid group of each vertex, or NULL */
	uint8_t* off_pose;	/* vertex left short of its target by the previous step */
	uint8_t* modified;	/* vertex moved short of its target in this step */
	uint8_t* flag;		/* vertex is a corner of an intersecting pair this round */
	uint8_t* halvings;	/* how often a vertex has been pulled back this step */
	uint8_t* candidate; /* triangle to search this round */
	sere_bvh* bvh;
};

/* Eight consecutive triangles share one walk down the tree. */
typedef struct pair_group
{
	const int32_t* tri;
	const float *x, *y, *z;
	int32_t first; /* the triangle of lane 0 */
	/* Triangles that search (all when NULL); a pair of two searching triangles is taken from the
	 * lower one only, so every pair is tested once. */
	const uint8_t* candidate;
	uint8_t* flag; /* when not NULL, the corners of both triangles of every pair are flagged */
	/* When not NULL: pairs whose six corners share a group and all moved with it skip the test. */
	const int32_t* group;
	const uint8_t *off_pose, *modified;
	int64_t count;
} pair_group;

/* All six corners in one rigid group, each at the caller's target both before and after this
 * step: the pair moved as one rigid body, so it cannot have come to intersect. */
static int moved_rigidly( const pair_group* g, const int32_t* s, const int32_t* o )
{
	int32_t k = g->group[s[0]];
	for ( int c = 0; c < 3; ++c )
	{
		if ( g->group[s[c]] != k || g->group[o[c]] != k || g->off_pose[s[c]] | g->modified[s[c]] ||
			 g->off_pose[o[c]] | g->modified[o[c]] )
		{
			return 0;
		}
	}
	return 1;
}

static void pair_visit( void* context, int32_t other, uint32_t lanes )
{
	pair_group* g = context;
	const int32_t* o = g->tri + 3 * other;
	while ( lanes != 0 )
	{
		int k = __builtin_ctz( lanes );
		lanes &= lanes - 1;
		int32_t self = g->first + k;
		if ( other == self || ( other < self && ( g->candidate == NULL || g->candidate[other] ) ) )
		{
			continue;
		}
		const int32_t* s = g->tri + 3 * self;
		if ( ( g->group != NULL && moved_rigidly( g, s, o ) ) || !triangles_intersect( g->x, g->y, g->z, s, o ) )
		{
			continue;
		}
		++g->count;
		if ( g->flag != NULL )
		{
			for ( int c = 0; c < 3; ++c )
			{
				/* Every writer stores the same value, so the result does not depend on the order. */
#pragma omp atomic write
				g->flag[s[c]] = 1;
#pragma omp atomic write
				g->flag[o[c]] = 1;
			}
		}
	}
}

/* Intersecting pairs among the triangles [first, first + 8) whose `candidate` flag is set (all
 * when candidate is NULL). */
static int64_t pair_search( const sere_bvh* bvh, const int32_t* tri, int32_t triangle_count, const float* x,
							const float* y, const float* z, int32_t first, const uint8_t* candidate, uint8_t* flag,
							const struct sere_pierce* rigid )
{
	pair_group g = { tri, x, y, z, first, candidate, flag, NULL, NULL, NULL, 0 };
	if ( rigid != NULL )
	{
		g.group = rigid->group;
		g.off_pose = rigid->off_pose;
		g.modified = rigid->modified;
	}
	sere_bvh_group boxes;
	boxes.count = triangle_count - first < SERE_BVH_WIDTH ? triangle_count - first : SERE_BVH_WIDTH;
	int any = 0;
	for ( int k = 0; k < boxes.count; ++k )
	{
		float lo[3], hi[3];
		triangle_box( x, y, z, tri + 3 * ( first + k ), lo, hi );
		int use = candidate == NULL || candidate[first + k];
		any |= use;
		boxes.lo_x[k] = use ? lo[0] : NAN;
		boxes.lo_y[k] = lo[1];
		boxes.lo_z[k] = lo[2];
		boxes.hi_x[k] = hi[0];
		boxes.hi_y[k] = hi[1];
		boxes.hi_z[k] = hi[2];
	}
	if ( any )
	{
		sere_bvh_query_group( bvh, &boxes, pair_visit, &g );
	}
	return g.count;
}

int64_t sere_mesh_count_intersections( const sere_bvh* bvh, const int32_t* tri, int32_t triangle_count, const float* x,
									   const float* y, const float* z, int32_t threads )
{
	int64_t total = 0;
	int32_t groups = ( triangle_count + SERE_BVH_WIDTH - 1 ) / SERE_BVH_WIDTH;
#pragma omp parallel for num_threads( sere_team_for( threads ) ) schedule( dynamic, 32 ) reduction( + : total )
	for ( int32_t b = 0; b < groups; ++b )
	{
		total += pair_search( bvh, tri, triangle_count, x, y, z, b * SERE_BVH_WIDTH, NULL, NULL, NULL );
	}
	return total;
}

/* Pull-backs halve the remaining move this many times before undoing it. */
#define PIERCE_HALVINGS 4
#define PIERCE_ROUNDS	32

void sere_pierce_destroy( sere_pierce* pierce )
{
	if ( pierce == NULL )
	{
		return;
	}
	sere_free( pierce->tri );
	sere_free( pierce->group );
	sere_free( pierce->off_pose );
	sere_free( pierce->modified );
	sere_free( pierce->flag );
	sere_free( pierce->halvings );
	sere_free( pierce->candidate );
	sere_bvh_destroy( pierce->bvh );
	free( pierce );
}

sere_status sere_pierce_create( const int32_t* tri, int32_t triangle_count, int32_t vertex_count, const float* x,
								const float* y, const float* z, const int32_t* rigid_group, sere_pierce** out )
{
	if ( out == NULL )
	{
		return SERE_ERR_ARGUMENT;
	}
	*out = NULL;
	if ( tri == NULL || triangle_count < 1 || vertex_count < 3 || triangle_count > INT32_MAX / 3 - SERE_PAD )
	{
		return SERE_ERR_ARGUMENT;
	}
	sere_pierce* p = calloc( 1, sizeof( sere_pierce ) );
	if ( p == NULL )
	{
		return SERE_ERR_MEMORY;
	}
	p->vertex_count = vertex_count;
	p->triangle_count = triangle_count;
	p->tri = sere_alloc( (size_t) sere_pad( 3 * triangle_count ) * sizeof( int32_t ) );
	p->flag = sere_alloc( (size_t) sere_pad( vertex_count ) );
	p->halvings = sere_alloc( (size_t) sere_pad( vertex_count ) );
	p->off_pose = sere_alloc( (size_t) sere_pad( vertex_count ) );
	p->modified = sere_alloc( (size_t) sere_pad( vertex_count ) );
	p->candidate = sere_alloc( (size_t) sere_pad( triangle_count ) );
	if ( rigid_group != NULL )
	{
		p->group = sere_alloc( (size_t) sere_pad( vertex_count ) * sizeof( int32_t ) );
	}
	if ( p->tri == NULL || p->flag == NULL || p->halvings == NULL || p->off_pose == NULL || p->modified == NULL ||
		 p->candidate == NULL || ( rigid_group != NULL && p->group == NULL ) )
	{
		sere_pierce_destroy( p );
		return SERE_ERR_MEMORY;
	}
	memcpy( p->tri, tri, 3 * (size_t) triangle_count * sizeof( int32_t ) );
	if ( rigid_group != NULL )
	{
		memcpy( p->group, rigid_group, (size_t) vertex_count * sizeof( int32_t ) );
	}
	sere_status status = sere_bvh_create( tri, triangle_count, vertex_count, x, y, z, &p->bvh );
	if ( status != SERE_OK )
	{
		sere_pierce_destroy( p );
		return status;
	}
	*out = p;
	return SERE_OK;
}

void sere_skel_pierce_rest( sere_pierce* pierce )
{
	memset( pierce->off_pose, 0, (size_t) pierce->vertex_count );
}

sere_status sere_pierce_set_threads( sere_pierce* pierce, int32_t threads )
{
	sere_status status = pierce == NULL ? SERE_ERR_ARGUMENT : sere_threads_store( &pierce->threads, threads );
	return status == SERE_OK ? sere_bvh_set_threads( pierce->bvh, threads ) : status;
}

const sere_bvh* sere_pierce_bvh( const sere_pierce* pierce )
{
	return pierce->bvh;
}

static int moved( const float* px, const float* py, const float* pz, const float* x, const float* y, const float* z,
				  int32_t i )
{
	return x[i] != px[i] || y[i] != py[i] || z[i] != pz[i];
}

sere_status sere_pierce_step( sere_pierce* p, const float* px, const float* py, const float* pz, float* x, float* y,
							  float* z, float margin, sere_pierce_stats* stats )
{
	if ( p == NULL || px == NULL || py == NULL || pz == NULL || x == NULL || y == NULL || z == NULL ||
		 !( margin >= 0.0f ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	sere_pierce_stats st = { 0, 0, 0, 0, 0 };
	bool rebuilt = false;
	sere_status status = sere_bvh_update( p->bvh, px, py, pz, SERE_BVH_REBUILD_RATIO, &rebuilt );
	if ( status != SERE_OK )
	{
		return status;
	}
	st.rebuilt = rebuilt;
	int32_t n = p->vertex_count, f = p->triangle_count;
	if ( !sere_array_finite( ( const float* const[] ){ x, y, z }, 3, n, p->threads ) )
	{
		return SERE_ERR_NONFINITE;
	}
	/* The seed's check: no vertex passes through the mesh as it was. */
	memset( p->modified, 0, (size_t) n );
	st.shortened = pierce_limit( p->bvh, p->tri, px, py, pz, x, y, z, n, margin, p->modified, p->threads );

	/* Then no triangle may end up through another. Only triangles with a moving corner can
	 * meet a new partner; later rounds search around the vertices just pulled back. */
	memset( p->halvings, 0, (size_t) n );
#pragma omp parallel for num_threads( sere_team_for( p->threads ) ) schedule( static )
	for ( int32_t t = 0; t < f; ++t )
	{
		const int32_t* c = p->tri + 3 * t;
		p->candidate[t] = (uint8_t) ( moved( px, py, pz, x, y, z, c[0] ) || moved( px, py, pz, x, y, z, c[1] ) ||
									  moved( px, py, pz, x, y, z, c[2] ) );
	}
	for ( ;; )
	{
		status = sere_bvh_refit( p->bvh, x, y, z );
		if ( status != SERE_OK )
		{
			return status;
		}
		if ( st.rounds == PIERCE_ROUNDS )
		{
			/* The previous state did not intersect; going back to it always succeeds. */
			memcpy( x, px, (size_t) n * sizeof( float ) );
			memcpy( y, py, (size_t) n * sizeof( float ) );
			memcpy( z, pz, (size_t) n * sizeof( float ) );
			memset( p->modified, 1, (size_t) n );
			st.reverted = 1;
			status = sere_bvh_refit( p->bvh, x, y, z );
			break;
		}
		memset( p->flag, 0, (size_t) n );
		int64_t found = 0;
		int32_t groups = ( f + SERE_BVH_WIDTH - 1 ) / SERE_BVH_WIDTH;
#pragma omp parallel for num_threads( sere_team_for( p->threads ) ) schedule( dynamic, 32 ) reduction( + : found )
		for ( int32_t b = 0; b < groups; ++b )
		{
			found += pair_search( p->bvh, p->tri, f, x, y, z, b * SERE_BVH_WIDTH, p->candidate, p->flag,
								  p->group != NULL ? p : NULL );
		}
		if ( found == 0 )
		{
			break;
		}
		++st.rounds;
		int32_t pulled = 0;
#pragma omp parallel for num_threads( sere_team_for( p->threads ) ) schedule( static ) reduction( + : pulled )
		for ( int32_t i = 0; i < n; ++i )
		{
			if ( !p->flag[i] || !moved( px, py, pz, x, y, z, i ) )
			{
				continue;
			}
			if ( p->halvings[i] < PIERCE_HALVINGS )
			{
				x[i] = 0.5f * ( x[i] + px[i] );
				y[i] = 0.5f * ( y[i] + py[i] );
				z[i] = 0.5f * ( z[i] + pz[i] );
				++p->halvings[i];
			}
			else
			{
				x[i] = px[i];
				y[i] = py[i];
				z[i] = pz[i];
			}
			p->modified[i] = 1;
			++pulled;
		}
		st.pulled_back += pulled;
#pragma omp parallel for num_threads( sere_team_for( p->threads ) ) schedule( static )
		for ( int32_t t = 0; t < f; ++t )
		{
			const int32_t* c = p->tri + 3 * t;
			p->candidate[t] = p->flag[c[0]] | p->flag[c[1]] | p->flag[c[2]];
		}
	}
	memcpy( p->off_pose, p->modified, (size_t) n );
	if ( stats != NULL )
	{
		*stats = st;
	}
	return status;
}
