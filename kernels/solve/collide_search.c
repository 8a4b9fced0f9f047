/* sere — vertex–triangle detection: the tree query of a vertex block, the separating-plane bound that lists candidate
 * pairs (see SKIN) and the exact closest-point test, eight pairs at a time. _GNU_SOURCE: sched_getaffinity for
 * internal/team.h. */
#define _GNU_SOURCE

#include "solve/internal/collide_shared.h"

/* closest_point for CLOSEST_LANES point–triangle pairs at once, as selects instead of branches:
 * every region's result is formed by the same operations as in closest_point and the first
 * region whose test holds is kept, so each lane gets closest_point's bits. A lane that reaches
 * the degenerate fallback is flagged in slow (its outputs are not meaningful) for the caller to
 * redo with closest_point. Rows are x, y, z; columns are lanes. (The inputs are read only; they
 * are not const because C17 does not convert float[3][8] to const float[3][8].) */
static void closest_lanes( float p[3][CLOSEST_LANES], float a[3][CLOSEST_LANES], float b[3][CLOSEST_LANES],
						   float c[3][CLOSEST_LANES], float w[3][CLOSEST_LANES], float q[3][CLOSEST_LANES],
						   float d2[CLOSEST_LANES], int32_t slow[CLOSEST_LANES] )
{
#pragma omp simd
	for ( int l = 0; l < CLOSEST_LANES; ++l )
	{
		float ab[3], ac[3], bc[3], ap[3], bp[3], cp[3];
		for ( int r = 0; r < 3; ++r )
		{
			ab[r] = b[r][l] - a[r][l], ac[r] = c[r][l] - a[r][l], bc[r] = c[r][l] - b[r][l];
			ap[r] = p[r][l] - a[r][l], bp[r] = p[r][l] - b[r][l], cp[r] = p[r][l] - c[r][l];
		}
		float d1 = ab[0] * ap[0] + ab[1] * ap[1] + ab[2] * ap[2];
		float d2a = ac[0] * ap[0] + ac[1] * ap[1] + ac[2] * ap[2];
		float d3 = ab[0] * bp[0] + ab[1] * bp[1] + ab[2] * bp[2];
		float d4 = ac[0] * bp[0] + ac[1] * bp[1] + ac[2] * bp[2];
		float d5 = ab[0] * cp[0] + ab[1] * cp[1] + ab[2] * cp[2];
		float d6 = ac[0] * cp[0] + ac[1] * cp[1] + ac[2] * cp[2];
		float vc = d1 * d4 - d3 * d2a;
		float vb = d5 * d2a - d1 * d6;
		float va = d3 * d6 - d5 * d4;
		float sum = va + vb + vc;

		/* the regions in closest_point's order, each only if none before it holds (& and |, not
		 * && and ||: no branches, so the loop vectorizes) */
		int at_a = ( d1 <= 0.0f ) & ( d2a <= 0.0f );
		int at_b = !at_a & ( d3 >= 0.0f ) & ( d4 <= d3 );
		int at_c = !at_a & !at_b & ( d6 >= 0.0f ) & ( d5 <= d6 );
		int vertex = at_a | at_b | at_c;
		int on_ab = !vertex & ( vc <= 0.0f ) & ( d1 >= 0.0f ) & ( d3 <= 0.0f ) & ( d1 - d3 > 0.0f );
		int on_ac = !vertex & !on_ab & ( vb <= 0.0f ) & ( d2a >= 0.0f ) & ( d6 <= 0.0f ) & ( d2a - d6 > 0.0f );
		int on_bc = !vertex & !on_ab & !on_ac & ( va <= 0.0f ) & ( d4 - d3 >= 0.0f ) & ( d5 - d6 >= 0.0f ) &
					( ( d4 - d3 ) + ( d5 - d6 ) > 0.0f );
		int edge = on_ab | on_ac | on_bc;
		float ab2 = ab[0] * ab[0] + ab[1] * ab[1] + ab[2] * ab[2];
		float ac2 = ac[0] * ac[0] + ac[1] * ac[1] + ac[2] * ac[2];
		int face =
			!vertex & !edge & ( vb >= 0.0f ) & ( vc >= 0.0f ) & ( vb + vc <= sum ) & ( sum > 0x1p-20f * ab2 * ac2 );

		float s_ab = d1 / ( d1 - d3 );
		float s_ac = d2a / ( d2a - d6 );
		float s_bc = ( d4 - d3 ) / ( ( d4 - d3 ) + ( d5 - d6 ) );
		float v_face = vb / sum, t_face = vc / sum;
		float u = at_a ? 1.0f : ( on_ab ? 1.0f - s_ab : ( on_ac ? 1.0f - s_ac : 0.0f ) );
		float v = at_b ? 1.0f : ( on_ab ? s_ab : ( on_bc ? 1.0f - s_bc : 0.0f ) );
		float t = at_c ? 1.0f : ( on_ac ? s_ac : ( on_bc ? s_bc : 0.0f ) );
		u = face ? 1.0f - v_face - t_face : u;
		v = face ? v_face : v;
		t = face ? t_face : t;
		float dist2 = 0.0f;
		for ( int r = 0; r < 3; ++r )
		{
			float point = at_a ? a[r][l] : ( at_b ? b[r][l] : c[r][l] );
			point = on_ab ? a[r][l] + s_ab * ab[r] : point;
			point = on_ac ? a[r][l] + s_ac * ac[r] : point;
			point = on_bc ? b[r][l] + s_bc * bc[r] : point;
			point = face ? a[r][l] + v_face * ab[r] + t_face * ac[r] : point;
			q[r][l] = point;
			float d = p[r][l] - point;
			dist2 += d * d;
		}
		w[0][l] = u, w[1][l] = v, w[2][l] = t;
		d2[l] = dist2;
		slow[l] = !( vertex || edge || face );
	}
}

_Static_assert( SERE_BVH_WIDTH <= 8, "a group's lane marks are two bytes per vertex" );

_Static_assert( DETECT_BLOCK % SERE_BVH_WIDTH == 0, "query groups start at multiples of the width" );

/* Sets (set) or clears the lane marks of the group whose lane 0 is vertex c->first (lane_bits):
 * a triangle with a lane's vertex as a corner is not a contact candidate for the lane, one with a
 * neighbour of it only with the closest point inside its face. */
static void mark_lanes( detect_context* c, bool set )
{
	int32_t g = c->first / SERE_BVH_WIDTH;
	for ( int32_t e = c->mark_offset[g]; e < c->mark_offset[g + 1]; ++e )
	{
		c->mark[c->mark_vertex[e]] = set ? c->mark_bits[e] : 0;
	}
}

/* Appends the contact of a vertex–triangle pair found within the thickness. */
static void detect_emit( detect_context* c, int32_t vertex, int32_t t, const float p[3], const float a[3],
						 const float b[3], const float cc[3], const float w[3], const float q[3], float d2 )
{
	c->found += 1;
	if ( c->used < c->capacity )
	{
		float ab[3] = { b[0] - a[0], b[1] - a[1], b[2] - a[2] };
		float ac[3] = { cc[0] - a[0], cc[1] - a[1], cc[2] - a[2] };
		float n[3] = { ab[1] * ac[2] - ab[2] * ac[1], ab[2] * ac[0] - ab[0] * ac[2], ab[0] * ac[1] - ab[1] * ac[0] };
		float s = ( p[0] - q[0] ) * n[0] + ( p[1] - q[1] ) * n[1] + ( p[2] - q[2] ) * n[2];
		c->buffer[c->used++] = ( sere_contact ){ vertex, t, w[0], w[1], w[2], sqrtf( d2 ), s < 0.0f ? -1.0f : 1.0f };
	}
}

/* The floor's detect_emit: the contact of the recorded pair written where the search writes it,
 * with the values already there (times one). */
static void touch_emit( detect_context* c, int32_t vertex, int32_t t )
{
	c->found += 1;
	if ( c->used < c->capacity )
	{
		sere_contact* k = c->buffer + c->used++;
		float one = c->one;
		*k = ( sere_contact ){ vertex, t, k->u * one, k->v * one, k->w * one, k->distance * one, k->side * one };
	}
}

/* The sum of a batch's gathered points (the floor's use of its loads). */
static float sum_points( float p[3][CLOSEST_LANES], float a[3][CLOSEST_LANES], float b[3][CLOSEST_LANES],
						 float cc[3][CLOSEST_LANES] )
{
	return ( sum_rows( p, 3 ) + sum_rows( a, 3 ) ) + ( sum_rows( b, 3 ) + sum_rows( cc, 3 ) );
}

/* For CLOSEST_LANES point–triangle pairs: bit l set unless separating directions put the point
 * farther than list_radius from the triangle. With n̂ the unit normal, |p − x|² = ((p − x) · n̂)²
 * + |p' − x|² for x in the triangle and p' the projection of p onto its plane; the first term is
 * ((p − a) · n̂)² exactly, and the in-plane distance is bounded by the gaps (interval_gap) on the
 * in-plane directions: each edge's outward normal (edge × n̂) and each edge's direction, the
 * latter bounding the corner regions within cos 30° on a triangle of 60° angles. A triangle whose
 * sin² of the corner angle is below 2⁻²⁰ (closest_lanes' degenerate case) is always kept. */
static uint32_t bound_lanes( const detect_context* c, float p[3][CLOSEST_LANES], float a[3][CLOSEST_LANES],
							 float b[3][CLOSEST_LANES], float cc[3][CLOSEST_LANES] )
{
	int32_t keep[CLOSEST_LANES];
#pragma omp simd
	for ( int l = 0; l < CLOSEST_LANES; ++l )
	{
		float ab[3], ac[3], bc[3], ap[3];
		for ( int r = 0; r < 3; ++r )
		{
			ab[r] = b[r][l] - a[r][l], ac[r] = cc[r][l] - a[r][l], bc[r] = cc[r][l] - b[r][l];
			ap[r] = p[r][l] - a[r][l];
		}
		float n[3] = { ab[1] * ac[2] - ab[2] * ac[1], ab[2] * ac[0] - ab[0] * ac[2], ab[0] * ac[1] - ab[1] * ac[0] };
		float nn = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
		float ab2 = ab[0] * ab[0] + ab[1] * ab[1] + ab[2] * ab[2];
		float ac2 = ac[0] * ac[0] + ac[1] * ac[1] + ac[2] * ac[2];
		int degenerate = !( nn > 0x1p-20f * ab2 * ac2 );
		float inv = 1.0f / sqrtf( degenerate ? 1.0f : nn );
		float u[3] = { n[0] * inv, n[1] * inv, n[2] * inv };
		float plane = ap[0] * u[0] + ap[1] * u[1] + ap[2] * u[2];
		/* in-plane directions: edges ab, bc, ca, and their outward normals edge × n̂, left at
		 * the edge's length (|e × n̂| = |e|, e lying in the plane), corners relative to a. A gap
		 * G along a direction of length² ee is G / √ee, so plane² + (G / √ee)² ≥ r² is tested
		 * as plane² ee + G² ≥ r² ee: no square root or division per direction (they were a
		 * third of the bound's time). A zero-length edge tells nothing. */
		float far[3] = { fabsf( p[0][l] ), fabsf( p[1][l] ), fabsf( p[2][l] ) };
		for ( int r = 0; r < 3; ++r )
		{
			float m = fabsf( a[r][l] ) > fabsf( b[r][l] ) ? fabsf( a[r][l] ) : fabsf( b[r][l] );
			m = m > fabsf( cc[r][l] ) ? m : fabsf( cc[r][l] );
			far[r] = far[r] > m ? far[r] : m;
		}
		float radius = list_radius( c, far );
		float r2 = radius * radius, plane2 = plane * plane;
		int beyond = plane2 >= r2;
		const float* edge[3] = { ab, bc, ac };
		for ( int k = 0; k < 3; ++k )
		{
			const float* e = edge[k];
			float m[3] = { e[1] * u[2] - e[2] * u[1], e[2] * u[0] - e[0] * u[2], e[0] * u[1] - e[1] * u[0] };
			float ee = e[0] * e[0] + e[1] * e[1] + e[2] * e[2];
			const float* dir[2] = { e, m };
			for ( int j = 0; j < 2; ++j )
			{
				const float* d = dir[j];
				float pb = ab[0] * d[0] + ab[1] * d[1] + ab[2] * d[2];
				float pc = ac[0] * d[0] + ac[1] * d[1] + ac[2] * d[2];
				float pp = ap[0] * d[0] + ap[1] * d[1] + ap[2] * d[2];
				float lo = pb < pc ? pb : pc, hi = pb < pc ? pc : pb;
				lo = lo < 0.0f ? lo : 0.0f, hi = hi > 0.0f ? hi : 0.0f;
				float gap = interval_gap( pp, pp, lo, hi );
				beyond |= ( ee > 0.0f ) & ( gap > 0.0f ) & ( plane2 * ee + gap * gap >= r2 * ee );
			}
		}
		keep[l] = degenerate | !beyond;
	}
	uint32_t mask = 0;
	for ( int l = 0; l < CLOSEST_LANES; ++l )
	{
		mask |= (uint32_t) ( keep[l] != 0 ) << l;
	}
	return mask;
}

/* Gathers the points of buffered vertex–triangle pairs start .. start + CLOSEST_LANES − 1 (lanes
 * past the end repeat the last pair). */
static void gather_pairs( const detect_context* c, int32_t start, int32_t count, float p[3][CLOSEST_LANES],
						  float a[3][CLOSEST_LANES], float b[3][CLOSEST_LANES], float cc[3][CLOSEST_LANES] )
{
	for ( int32_t l = 0; l < CLOSEST_LANES; ++l )
	{
		int32_t k = start + ( l < count ? l : count - 1 );
		int32_t vertex = c->pair_item[k];
		const int32_t* v = c->tri + 3 * (size_t) c->pair_target[k];
		p[0][l] = c->x[vertex], p[1][l] = c->y[vertex], p[2][l] = c->z[vertex];
		a[0][l] = c->x[v[0]], a[1][l] = c->y[v[0]], a[2][l] = c->z[v[0]];
		b[0][l] = c->x[v[1]], b[1][l] = c->y[v[1]], b[2][l] = c->z[v[1]];
		cc[0][l] = c->x[v[2]], cc[1][l] = c->y[v[2]], cc[2][l] = c->z[v[2]];
	}
}

/* Listing: keeps in the pair buffer (in order) only the pairs bound_lanes keeps and lists them;
 * the others cannot be contacts now either (the bound is below the distance, the radius above
 * the thickness). */
static void list_vertex_pairs( detect_context* c )
{
	int32_t kept = 0;
	for ( int32_t start = 0; start < c->pair_count; start += CLOSEST_LANES )
	{
		int32_t count = c->pair_count - start < CLOSEST_LANES ? c->pair_count - start : CLOSEST_LANES;
		float p[3][CLOSEST_LANES], a[3][CLOSEST_LANES], b[3][CLOSEST_LANES], cc[3][CLOSEST_LANES];
		gather_pairs( c, start, count, p, a, b, cc );
		uint32_t keep;
		if ( replaying( c ) )
		{
			keep = recorded_mask( c );
			c->run->sink += sum_points( p, a, b, cc );
		}
		else
		{
			keep = traced_mask( c, bound_lanes( c, p, a, b, cc ) & ( ( 1u << count ) - 1u ) );
		}
		if ( c->run != NULL )
		{
			c->run->bound_pairs += count;
		}
		kept = keep_pairs( c, start, keep, kept, true );
	}
	c->pair_count = kept;
}

/* The exact test of the buffered pairs, CLOSEST_LANES at a time, in the order they were
 * buffered (the tree's, then the lanes'), so the contact list does not depend on the batching. */
void sere_coll_detect_flush( detect_context* c )
{
	if ( c->listing )
	{
		list_vertex_pairs( c );
	}
	for ( int32_t start = 0; start < c->pair_count; start += CLOSEST_LANES )
	{
		int32_t count = c->pair_count - start < CLOSEST_LANES ? c->pair_count - start : CLOSEST_LANES;
		float p[3][CLOSEST_LANES], a[3][CLOSEST_LANES], b[3][CLOSEST_LANES], cc[3][CLOSEST_LANES];
		float w[3][CLOSEST_LANES], q[3][CLOSEST_LANES], d2[CLOSEST_LANES];
		int32_t slow[CLOSEST_LANES];
		/* lanes past the end repeat the last pair and are ignored */
		gather_pairs( c, start, count, p, a, b, cc );
		if ( c->run != NULL )
		{
			c->run->exact_pairs += count;
		}
		float* gap = listed_gaps( c, start );
		if ( replaying( c ) )
		{
			c->run->sink += sum_points( p, a, b, cc );
			for ( int32_t l = 0; gap != NULL && l < count; ++l )
			{
				gap[l] *= c->one;
			}
			for ( uint32_t emitted = recorded_mask( c ); emitted != 0; emitted &= emitted - 1 )
			{
				int32_t l = __builtin_ctz( emitted );
				touch_emit( c, c->pair_item[start + l], c->pair_target[start + l] );
			}
			continue;
		}
		closest_lanes( p, a, b, cc, w, q, d2, slow );
		if ( gap != NULL )
		{
			int32_t sharp[CLOSEST_LANES];
			sine2_at_least( a, b, a, cc, 0x1p-8f, sharp );
			for ( int l = 0; l < CLOSEST_LANES; ++l )
			{
				sharp[l] &= !slow[l];
			}
			keep_gaps( gap, count, d2, sharp );
		}
		uint32_t candidates = 0, emitted = 0;
		for ( int32_t l = 0; l < count; ++l )
		{
			candidates |= (uint32_t) ( slow[l] | ( d2[l] < c->h2 ) ) << l;
		}
		while ( candidates != 0 )
		{
			int32_t l = __builtin_ctz( candidates );
			candidates &= candidates - 1;
			float pl[3] = { p[0][l], p[1][l], p[2][l] }, al[3] = { a[0][l], a[1][l], a[2][l] };
			float bl[3] = { b[0][l], b[1][l], b[2][l] }, cl[3] = { cc[0][l], cc[1][l], cc[2][l] };
			float wl[3] = { w[0][l], w[1][l], w[2][l] }, ql[3] = { q[0][l], q[1][l], q[2][l] };
			float dl = slow[l] ? closest_point( pl, al, bl, cl, wl, ql ) : d2[l];
			bool face = wl[0] > 0.0f && wl[1] > 0.0f && wl[2] > 0.0f;
			if ( dl < c->h2 && ( face || !c->pair_near[start + l] ) )
			{
				detect_emit( c, c->pair_item[start + l], c->pair_target[start + l], pl, al, bl, cl, wl, ql, dl );
				emitted |= 1u << l;
			}
		}
		traced_mask( c, emitted );
	}
	c->pair_count = 0;
}

/* Buffers the pairs of one triangle with every group vertex whose cube overlaps its box but the
 * triangle's own corners (the lane marks), flagging the vertices joined by a mesh edge to a
 * corner: such a vertex lies in the sheet right beside the triangle, and where edges are shorter
 * than the thickness (fine outline and vein sampling, a shrunk blade) it is closer than the
 * thickness without any collision, its closest point on an edge or corner, and a push along the
 * normal would only buckle the sheet. It is a contact only when its closest point lies inside
 * the face, which takes a fold of the sheet past a right angle within one ring: the two
 * triangles of an edge closing on each other like a book, which unchecked let the vertex pass
 * through (on the maple at 800 points, at its base). */
static void detect_visit( void* context, int32_t t, uint32_t lanes )
{
	detect_context* c = context;
	const int32_t* v = c->tri + 3 * (size_t) t;
	lane_bits m = (lane_bits) ( c->mark[v[0]] | c->mark[v[1]] | c->mark[v[2]] );
	lanes &= ~self_lanes( m );
	uint32_t near = near_lanes( m );

	while ( lanes != 0 )
	{
		if ( c->pair_count == PAIR_BUFFER )
		{
			sere_coll_detect_flush( c );
		}
		int32_t k = __builtin_ctz( lanes );
		c->pair_target[c->pair_count] = t;
		c->pair_item[c->pair_count] = c->first + k;
		c->pair_near[c->pair_count] = (uint8_t) ( near >> k & 1u );
		c->pair_count += 1;
		lanes &= lanes - 1;
	}
}

/* Queries the groups of vertex block `block` (lanes are vertices: detect_visit). */
int sere_coll_detect_vertex_block( detect_context* c, const sere_bvh* bvh, int32_t block, int32_t n, float thickness )
{
	int bad = 0;
	bool replay = replaying( c );
	int32_t end = ( block + 1 ) * DETECT_BLOCK < n ? ( block + 1 ) * DETECT_BLOCK : n;
	for ( int32_t first = block * DETECT_BLOCK; first < end; first += SERE_BVH_WIDTH )
	{
		sere_bvh_group group;
		group.count = end - first < SERE_BVH_WIDTH ? end - first : SERE_BVH_WIDTH;
		c->first = first;
		for ( int32_t k = 0; k < group.count; ++k )
		{
			float p[3];
			load3( c->x, c->y, c->z, first + k, p );
			if ( replay )
			{
				/* the walk is replayed: the lanes' boxes are not needed */
				c->run->sink += ( p[0] + p[1] ) + p[2];
				continue;
			}
			/* a NaN or infinite vertex leaves its lane non-finite: the query ignores it */
			bad |= !( isfinite( p[0] ) && isfinite( p[1] ) && isfinite( p[2] ) );
			float r = cull_radius( thickness, p ) + c->grow;
			group.lo_x[k] = p[0] - r, group.lo_y[k] = p[1] - r, group.lo_z[k] = p[2] - r;
			group.hi_x[k] = p[0] + r, group.hi_y[k] = p[1] + r, group.hi_z[k] = p[2] + r;
		}
		mark_lanes( c, true );
		if ( c->run != NULL )
		{
			sere_bvh_query_group_traced( bvh, &group, false, 0, &c->run->trace, detect_visit, c );
		}
		else
		{
			sere_bvh_query_group( bvh, &group, detect_visit, c );
		}
		mark_lanes( c, false );
	}
	sere_coll_detect_flush( c );
	return bad;
}
