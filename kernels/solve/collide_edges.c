/* sere — edge–edge detection: the edge table of a vertex block, its tree query, the plane bound and the exact
 * closest-segments test, eight pairs at a time. _GNU_SOURCE: sched_getaffinity for internal/team.h. */
#define _GNU_SOURCE

#include "solve/internal/collide_shared.h"

/* For CLOSEST_LANES segment pairs: bit l set unless separating directions put the segments
 * farther apart than list_radius: their common normal e × f (where they are not parallel to
 * within sin² 2⁻²⁰) and f's direction. The edge table (table_hits) already tested e's direction
 * and the planes across both edges, with a margin no larger. */
static uint32_t edge_bound_lanes( const detect_context* c, float a0[3][CLOSEST_LANES], float a1[3][CLOSEST_LANES],
								  float b0[3][CLOSEST_LANES], float b1[3][CLOSEST_LANES] )
{
	int32_t keep[CLOSEST_LANES];
#pragma omp simd
	for ( int l = 0; l < CLOSEST_LANES; ++l )
	{
		float u[3], v[3], w1[3], w0[3], w2[3];
		for ( int r = 0; r < 3; ++r )
		{
			u[r] = a1[r][l] - a0[r][l], v[r] = b1[r][l] - b0[r][l];
			w0[r] = b0[r][l] - a0[r][l], w1[r] = b1[r][l] - a0[r][l], w2[r] = u[r];
		}
		float n[3] = { u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0] };
		float nn = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
		float uu = u[0] * u[0] + u[1] * u[1] + u[2] * u[2], vv = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
		int skew = nn > 0x1p-20f * uu * vv;
		float far[3];
		for ( int r = 0; r < 3; ++r )
		{
			float m0 = fabsf( a0[r][l] ) > fabsf( a1[r][l] ) ? fabsf( a0[r][l] ) : fabsf( a1[r][l] );
			float m1 = fabsf( b0[r][l] ) > fabsf( b1[r][l] ) ? fabsf( b0[r][l] ) : fabsf( b1[r][l] );
			far[r] = m0 > m1 ? m0 : m1;
		}
		float radius = list_radius( c, far ), r2 = radius * radius;
		/* The directions at their own lengths: a gap G along a direction of length² dd is G / √dd,
		 * and G / √dd ≥ r is tested as G ≥ 0 and G² ≥ r² dd, without a square root or division. A
		 * direction of length 0 (parallel or zero-length segments) tells nothing. */
		float d[2][3], dd[2] = { skew ? nn : 0.0f, vv };
		for ( int r = 0; r < 3; ++r )
		{
			d[0][r] = n[r], d[1][r] = v[r];
		}
		int beyond = 0;
		for ( int k = 0; k < 2; ++k )
		{
			/* e's ends a0, a1 and f's b0, b1, relative to a0 */
			float pa = w2[0] * d[k][0] + w2[1] * d[k][1] + w2[2] * d[k][2];
			float q0 = w0[0] * d[k][0] + w0[1] * d[k][1] + w0[2] * d[k][2];
			float q1 = w1[0] * d[k][0] + w1[1] * d[k][1] + w1[2] * d[k][2];
			float gap =
				interval_gap( pa < 0.0f ? pa : 0.0f, pa > 0.0f ? pa : 0.0f, q0 < q1 ? q0 : q1, q0 < q1 ? q1 : q0 );
			beyond |= ( dd[k] > 0.0f ) & ( gap >= 0.0f ) & ( gap * gap >= r2 * dd[k] );
		}
		keep[l] = !beyond;
	}
	uint32_t mask = 0;
	for ( int l = 0; l < CLOSEST_LANES; ++l )
	{
		mask |= (uint32_t) ( keep[l] != 0 ) << l;
	}
	return mask;
}

/* closest_segments for CLOSEST_LANES segment pairs at once, as selects instead of branches: each
 * lane's result is formed by the same operations as in closest_segments, so it gets the same
 * bits (a zero-length or parallel lane computes quotients it then does not select). Rows are x,
 * y, z; columns are lanes. */
static void closest_segments_lanes( float p0[3][CLOSEST_LANES], float p1[3][CLOSEST_LANES], float q0[3][CLOSEST_LANES],
									float q1[3][CLOSEST_LANES], float w[2][CLOSEST_LANES], float d2[CLOSEST_LANES] )
{
#pragma omp simd
	for ( int l = 0; l < CLOSEST_LANES; ++l )
	{
		float d1[3], dd[3], r[3];
		for ( int k = 0; k < 3; ++k )
		{
			d1[k] = p1[k][l] - p0[k][l], dd[k] = q1[k][l] - q0[k][l], r[k] = p0[k][l] - q0[k][l];
		}
		float a = d1[0] * d1[0] + d1[1] * d1[1] + d1[2] * d1[2];
		float e = dd[0] * dd[0] + dd[1] * dd[1] + dd[2] * dd[2];
		float b = d1[0] * dd[0] + d1[1] * dd[1] + d1[2] * dd[2];
		float c = d1[0] * r[0] + d1[1] * r[1] + d1[2] * r[2];
		float f = dd[0] * r[0] + dd[1] * r[1] + dd[2] * r[2];
		float denom = a * e - b * b;
		float s = denom > 0x1p-20f * a * e ? clamp_unit( ( b * f - c * e ) / denom ) : 0.0f;
		float t = ( b * s + f ) / e;
		int low = !( e > 0.0f ) | ( t < 0.0f ), high = !low & ( t > 1.0f );
		float s_low = a > 0.0f ? clamp_unit( -c / a ) : 0.0f;
		float s_high = a > 0.0f ? clamp_unit( ( b - c ) / a ) : 0.0f;
		s = low ? s_low : ( high ? s_high : s );
		t = low ? 0.0f : ( high ? 1.0f : t );
		float dist2 = 0.0f;
		for ( int k = 0; k < 3; ++k )
		{
			float d = r[k] + s * d1[k] - t * dd[k];
			dist2 += d * d;
		}
		w[0][l] = s, w[1][l] = t;
		d2[l] = dist2;
	}
}

/* Appends the contact of edges e and f (e < f), closer than the thickness with both closest
 * points inside. */
static void detect_edge_emit( detect_context* c, int32_t e, int32_t f, const float a0[3], const float a1[3],
							  const float b0[3], const float b1[3] )
{
	c->edge_found += 1;
	if ( c->edge_used < c->capacity )
	{
		float w[2], d[3];
		float d2 = closest_segments( a0, a1, b0, b1, w, d );
		float u[3] = { a1[0] - a0[0], a1[1] - a0[1], a1[2] - a0[2] };
		float v[3] = { b1[0] - b0[0], b1[1] - b0[1], b1[2] - b0[2] };
		float n[3] = { u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0] };
		float side = d[0] * n[0] + d[1] * n[1] + d[2] * n[2];
		c->edge_buffer[c->edge_used++] = ( sere_edge_contact ){
			c->edge_end[2 * e], c->edge_end[2 * e + 1],		c->edge_end[2 * f], c->edge_end[2 * f + 1], w[0], w[1],
			sqrtf( d2 ),		side < 0.0f ? -1.0f : 1.0f,
		};
	}
}

/* The floor's detect_edge_emit: the ends' indices loaded as the search loads them, the contact
 * written where the search writes it with the values already there (times one). */
static void touch_edge_emit( detect_context* c, int32_t e, int32_t f )
{
	c->edge_found += 1;
	if ( c->edge_used < c->capacity )
	{
		sere_edge_contact* k = c->edge_buffer + c->edge_used++;
		float one = c->one;
		*k = ( sere_edge_contact ){
			c->edge_end[2 * e], c->edge_end[2 * e + 1], c->edge_end[2 * f], c->edge_end[2 * f + 1], k->s * one,
			k->t * one,			k->distance * one,		k->side * one,
		};
	}
}

/* The floor's edge_pair_counts: the rest positions it loads, added up (0 without them). */
static float touch_rest( const detect_context* c, int32_t e, int32_t f )
{
	if ( c->rest_x == NULL )
	{
		return 0.0f;
	}
	const int32_t *u = c->edge_end + 2 * (size_t) e, *v = c->edge_end + 2 * (size_t) f;
	int32_t ends[4] = { u[0], u[1], v[0], v[1] };
	float sum = 0.0f;
	for ( int k = 0; k < 4; ++k )
	{
		sum += ( c->rest_x[ends[k]] + c->rest_y[ends[k]] ) + c->rest_z[ends[k]];
	}
	return sum;
}

/* Whether a pair of edges within the thickness, closest inside both, is a contact: unless the
 * workspace has rest positions and the two segments lie closer than the thickness there too
 * (sere_collide_set_rest: neighbours in the sheet). */
static bool edge_pair_counts( const detect_context* c, int32_t e, int32_t f )
{
	if ( c->rest_x == NULL )
	{
		return true;
	}
	const int32_t *u = c->edge_end + 2 * (size_t) e, *v = c->edge_end + 2 * (size_t) f;
	float p0[3], p1[3], q0[3], q1[3], w[2], d[3];
	load3( c->rest_x, c->rest_y, c->rest_z, u[0], p0 );
	load3( c->rest_x, c->rest_y, c->rest_z, u[1], p1 );
	load3( c->rest_x, c->rest_y, c->rest_z, v[0], q0 );
	load3( c->rest_x, c->rest_y, c->rest_z, v[1], q1 );
	return !( closest_segments( p0, p1, q0, q1, w, d ) < c->h2 );
}

/* Gathers the ends of buffered edge pairs start .. start + CLOSEST_LANES − 1 (lanes past the end
 * repeat the last pair). */
static void gather_edge_pairs( const detect_context* c, int32_t start, int32_t count, float a0[3][CLOSEST_LANES],
							   float a1[3][CLOSEST_LANES], float b0[3][CLOSEST_LANES], float b1[3][CLOSEST_LANES] )
{
	for ( int32_t l = 0; l < CLOSEST_LANES; ++l )
	{
		int32_t k = start + ( l < count ? l : count - 1 );
		const int32_t* e = c->edge_end + 2 * (size_t) c->pair_item[k];
		const int32_t* f = c->edge_end + 2 * (size_t) c->pair_target[k];
		a0[0][l] = c->x[e[0]], a0[1][l] = c->y[e[0]], a0[2][l] = c->z[e[0]];
		a1[0][l] = c->x[e[1]], a1[1][l] = c->y[e[1]], a1[2][l] = c->z[e[1]];
		b0[0][l] = c->x[f[0]], b0[1][l] = c->y[f[0]], b0[2][l] = c->z[f[0]];
		b1[0][l] = c->x[f[1]], b1[1][l] = c->y[f[1]], b1[2][l] = c->z[f[1]];
	}
}

/* Listing: keeps in the pair buffer (in order) only the edge pairs edge_bound_lanes keeps and
 * lists them, as list_vertex_pairs. */
static void list_edge_pairs( detect_context* c )
{
	int32_t kept = 0;
	for ( int32_t start = 0; start < c->pair_count; start += CLOSEST_LANES )
	{
		int32_t count = c->pair_count - start < CLOSEST_LANES ? c->pair_count - start : CLOSEST_LANES;
		float a0[3][CLOSEST_LANES], a1[3][CLOSEST_LANES], b0[3][CLOSEST_LANES], b1[3][CLOSEST_LANES];
		gather_edge_pairs( c, start, count, a0, a1, b0, b1 );
		uint32_t keep;
		if ( replaying( c ) )
		{
			/* edge_bound_lanes' loads: the ends */
			keep = recorded_mask( c );
			c->run->sink += ( sum_rows( a0, 3 ) + sum_rows( a1, 3 ) ) + ( sum_rows( b0, 3 ) + sum_rows( b1, 3 ) );
		}
		else
		{
			keep = traced_mask( c, edge_bound_lanes( c, a0, a1, b0, b1 ) & ( ( 1u << count ) - 1u ) );
		}
		if ( c->run != NULL )
		{
			c->run->bound_pairs += count;
		}
		kept = keep_pairs( c, start, keep, kept, false );
	}
	c->pair_count = kept;
}

/* The exact test of the buffered edge pairs, CLOSEST_LANES at a time, in the order they were
 * buffered. A pair is a contact when it is closer than the thickness and both closest points
 * lie strictly inside their edges: where one is an end, that vertex is within the thickness of
 * the other edge's triangles, a vertex–triangle pair. */
void sere_coll_detect_edge_flush( detect_context* c )
{
	if ( c->listing )
	{
		list_edge_pairs( c );
	}
	for ( int32_t start = 0; start < c->pair_count; start += CLOSEST_LANES )
	{
		int32_t count = c->pair_count - start < CLOSEST_LANES ? c->pair_count - start : CLOSEST_LANES;
		float a0[3][CLOSEST_LANES], a1[3][CLOSEST_LANES], b0[3][CLOSEST_LANES], b1[3][CLOSEST_LANES];
		float w[2][CLOSEST_LANES], d2[CLOSEST_LANES];
		/* lanes past the end repeat the last pair and are ignored */
		gather_edge_pairs( c, start, count, a0, a1, b0, b1 );
		if ( c->run != NULL )
		{
			c->run->exact_pairs += count;
		}
		float* gap = listed_gaps( c, start );
		if ( replaying( c ) )
		{
			for ( int32_t l = 0; gap != NULL && l < count; ++l )
			{
				gap[l] *= c->one;
			}
			uint32_t tested = recorded_mask( c ), emitted = recorded_mask( c );
			float sum = ( sum_rows( a0, 3 ) + sum_rows( a1, 3 ) ) + ( sum_rows( b0, 3 ) + sum_rows( b1, 3 ) );
			for ( ; tested != 0; tested &= tested - 1 )
			{
				int32_t l = __builtin_ctz( tested );
				int32_t e = c->pair_item[start + l], f = c->pair_target[start + l];
				sum += touch_rest( c, e, f );
				if ( emitted >> l & 1u )
				{
					touch_edge_emit( c, e, f );
				}
			}
			c->run->sink += sum;
			continue;
		}
		closest_segments_lanes( a0, a1, b0, b1, w, d2 );
		if ( gap != NULL )
		{
			int32_t sharp[CLOSEST_LANES];
			sine2_at_least( a0, a1, b0, b1, 0x1p-10f, sharp );
			keep_gaps( gap, count, d2, sharp );
		}
		uint32_t hits = 0;
		for ( int32_t l = 0; l < count; ++l )
		{
			int inside = ( w[0][l] > 0.0f ) & ( w[0][l] < 1.0f ) & ( w[1][l] > 0.0f ) & ( w[1][l] < 1.0f );
			hits |= (uint32_t) ( inside & ( d2[l] < c->h2 ) ) << l;
		}
		traced_mask( c, hits );
		uint32_t emitted = 0;
		while ( hits != 0 )
		{
			int32_t l = __builtin_ctz( hits );
			hits &= hits - 1;
			float p0[3] = { a0[0][l], a0[1][l], a0[2][l] }, p1[3] = { a1[0][l], a1[1][l], a1[2][l] };
			float q0[3] = { b0[0][l], b0[1][l], b0[2][l] }, q1[3] = { b1[0][l], b1[1][l], b1[2][l] };
			int32_t e = c->pair_item[start + l], f = c->pair_target[start + l];
			if ( edge_pair_counts( c, e, f ) )
			{
				detect_edge_emit( c, e, f, p0, p1, q0, q1 );
				emitted |= 1u << l;
			}
		}
		traced_mask( c, emitted );
	}
	c->pair_count = 0;
}

/* Bit l set when row j = from + l of the table (8 rows) is a candidate for edge f = (f0, f1) with
 * ends p, q, box lo, hi and unit vector across fa: the row's edge comes before f (its lower end is
 * below f0: each pair is tested once), shares no end with it, has its grown box overlapping f's,
 * f lies beyond the row's margin neither on one side of the plane through the row's edge across
 * it nor past one of its ends along it, and the row's edge lies beyond it on neither side of the
 * plane through f across f. The plane across is where a flat sheet puts the edges beside it,
 * which boxes alone let through (on the flat Table 1 maple it takes the pairs left by the boxes
 * from 23 thousand to 10); the planes at the ends take the edges of the ring around the row's
 * ends, whose boxes overlap its grown box and which straddle the plane across (on the Table 1
 * maple's first listing search, the pairs left for edge_bound_lanes went from 20186 to 15230, and
 * a listing search took 2 to 5% less time on every shape of BM_collide_detect); the plane across
 * f is the first test seen from f's side, which edge_bound_lanes made only after the gathers (on
 * the dried, curled maple it takes the pairs of both kinds left for the bounds from 80385 to 60058,
 * and a dense searching detection 14 to 18% less time at 1 thread). All are separating directions
 * (interval_gap): f's ends p and q project relative to the row's lower end, the row's edge spans
 * [0, length]; the row's ends project relative to p, f spans 0 (both its ends lie on its plane
 * across, as the row's on its own). */
static inline uint32_t table_hits( const detect_context* c, int32_t from, const float lo[3], const float hi[3],
								   const float p[3], const float q[3], int32_t f0, int32_t f1, const float fa[3] )
{
	sere_m8 hit = sere_m8_all();
	sere_v8 sp = sere_v8_zero(), sq = sere_v8_zero(), tp = sere_v8_zero(), tq = sere_v8_zero();
	/* the row's lower end relative to p, and its direction, on f's across vector */
	sere_v8 ra = sere_v8_zero(), ua = sere_v8_zero();
	for ( int a = 0; a < 3; ++a )
	{
		hit = sere_m8_and( hit, sere_v8_le( sere_v8_splat( lo[a] ), sere_v8_load( c->table_hi[a] + from ) ) );
		hit = sere_m8_and( hit, sere_v8_ge( sere_v8_splat( hi[a] ), sere_v8_load( c->table_lo[a] + from ) ) );
		sere_v8 at = sere_v8_load( c->table_at[a] + from ), across = sere_v8_load( c->table_across[a] + from );
		sere_v8 along = sere_v8_load( c->table_along[a] + from );
		sere_v8 dp = sere_v8_sub( sere_v8_splat( p[a] ), at ), dq = sere_v8_sub( sere_v8_splat( q[a] ), at );
		sp = sere_v8_add( sp, sere_v8_mul( dp, across ) );
		sq = sere_v8_add( sq, sere_v8_mul( dq, across ) );
		tp = sere_v8_add( tp, sere_v8_mul( dp, along ) );
		tq = sere_v8_add( tq, sere_v8_mul( dq, along ) );
		sere_v8 f_across = sere_v8_splat( fa[a] );
		ra = sere_v8_sub( ra, sere_v8_mul( dp, f_across ) );
		ua = sere_v8_add( ua, sere_v8_mul( along, f_across ) );
	}
	sere_v8 margin = sere_v8_load( c->table_margin + from );
	sere_v8 low = sere_v8_sub( sere_v8_zero(), margin );
	sere_v8 high = sere_v8_add( sere_v8_load( c->table_length + from ), margin );
	sere_m8 beyond = sere_m8_or( sere_m8_and( sere_v8_gt( sp, margin ), sere_v8_gt( sq, margin ) ),
								 sere_m8_and( sere_v8_lt( sp, low ), sere_v8_lt( sq, low ) ) );
	beyond = sere_m8_or( beyond, sere_m8_or( sere_m8_and( sere_v8_gt( tp, high ), sere_v8_gt( tq, high ) ),
											 sere_m8_and( sere_v8_lt( tp, low ), sere_v8_lt( tq, low ) ) ) );
	sere_v8 rb = sere_v8_add( ra, sere_v8_mul( ua, sere_v8_load( c->table_length + from ) ) );
	beyond = sere_m8_or( beyond, sere_m8_or( sere_m8_and( sere_v8_gt( ra, margin ), sere_v8_gt( rb, margin ) ),
											 sere_m8_and( sere_v8_lt( ra, low ), sere_v8_lt( rb, low ) ) ) );
	sere_m8 skip = sere_m8_or( sere_i8_eq( c->table_upper + from, f0 ), sere_i8_eq( c->table_upper + from, f1 ) );
	skip = sere_m8_or( skip, sere_i8_gt( c->table_lower + from, f0 - 1 ) );
	return sere_m8_bits( sere_m8_and_not( hit, sere_m8_or( beyond, skip ) ) );
}

/* Tests the buffered candidate edges f against the rows of the lanes whose box overlaps their
 * triangle's (table_hits) and buffers the pairs that pass for the exact test. */
static void detect_edge_candidates( detect_context* c )
{
	bool replay = replaying( c );
	float sum = 0.0f;
	for ( int32_t k = 0; k < c->candidate_count; ++k )
	{
		int32_t f = c->candidate_edge[k];
		uint32_t lanes = c->candidate_lanes[k];
		int32_t f0 = c->edge_end[2 * f], f1 = c->edge_end[2 * f + 1];
		float p[3], q[3], lo[3], hi[3];
		load3( c->x, c->y, c->z, f0, p );
		load3( c->x, c->y, c->z, f1, q );
		float fa[3] = { c->across[0][f], c->across[1][f], c->across[2][f] };
		if ( replay )
		{
			/* table_hits' outcomes are recorded: its box of f is not needed */
			sum += ( ( p[0] + p[1] ) + p[2] ) + ( ( q[0] + q[1] ) + q[2] ) + ( ( fa[0] + fa[1] ) + fa[2] );
		}
		for ( int a = 0; !replay && a < 3; ++a )
		{
			lo[a] = p[a] < q[a] ? p[a] : q[a];
			hi[a] = p[a] < q[a] ? q[a] : p[a];
		}
		int32_t rows = c->table_lane[32 - __builtin_clz( lanes )];
		for ( int32_t from = c->table_lane[__builtin_ctz( lanes )]; from < rows; from += 8 )
		{
			uint32_t hits = replay ? recorded_mask( c )
								   : traced_mask( c, table_hits( c, from, lo, hi, p, q, f0, f1, fa ) &
														 ( rows - from >= 8 ? 0xffu : ( 1u << ( rows - from ) ) - 1 ) );
			while ( hits != 0 )
			{
				int32_t j = from + __builtin_ctz( hits );
				hits &= hits - 1;
				if ( c->pair_count == PAIR_BUFFER )
				{
					sere_coll_detect_edge_flush( c );
				}
				c->pair_item[c->pair_count] = c->table_edge[j];
				c->pair_target[c->pair_count] = f;
				c->pair_count += 1;
			}
		}
	}
	if ( replay )
	{
		c->run->sink += sum;
	}
	c->candidate_count = 0;
}

/* Buffers the edges f triangle t owns that may pair with an edge of the group (their lower end is
 * above the group's lowest lane vertex), with the group's lanes whose box overlaps t's, for
 * detect_edge_candidates. A pair is any two edges sharing no end: unlike a vertex and the
 * triangles beside it (detect_visit), edges a ring or two apart are not excluded from the search.
 * Two edges of a smooth sheet have their closest points at an end, and only where the sheet folds
 * back on itself do both fall inside, closer than the thickness; there the fold must be held
 * open. On the maple at 1500 points a folding tip let two edges joined through one mesh edge pass
 * through each other, and no rule excluding neighbours' edges by topology kept the six drying
 * runs of the tests free of crossings; the exact test excludes only the pairs that are that close
 * at rest (edge_pair_counts). */
static void detect_edge_visit( void* context, int32_t t, uint32_t lanes )
{
	detect_context* c = context;
	if ( c->candidate_count > CANDIDATES - 3 )
	{
		detect_edge_candidates( c );
	}
	const int32_t* owned = c->owned + 3 * (size_t) t;
	/* without branches: which owned edges pass is as good as random */
	for ( int r = 0; r < 3; ++r )
	{
		int32_t f = owned[r];
		int32_t f0 = c->edge_end[2 * ( f < 0 ? 0 : f )];
		c->candidate_edge[c->candidate_count] = f;
		c->candidate_lanes[c->candidate_count] = (uint8_t) lanes;
		c->candidate_count += ( f >= 0 ) & ( f0 > c->first );
	}
}

/* Adds the edges e .. end (at most LANE_EDGES) of vertex a to the table as lane k of group. The
 * lane's box is the box of those edges grown by the cull radius of its farthest corner. */
static void table_lane( detect_context* c, sere_bvh_group* group, int32_t k, int32_t a, int32_t e, int32_t end,
						float thickness )
{
	float lo[3] = { INFINITY, INFINITY, INFINITY }, hi[3] = { -INFINITY, -INFINITY, -INFINITY };
	float pa[3];
	load3( c->x, c->y, c->z, a, pa );
	int32_t from = c->table_lane[k] = c->table_count;
	if ( replaying( c ) )
	{
		/* the walk and the table's tests are replayed: only the loads and the rows' edges */
		float sum = ( pa[0] + pa[1] ) + pa[2];
		for ( int32_t i = e; i < end; ++i )
		{
			int32_t b = c->edge_end[2 * i + 1];
			sum += ( c->x[b] + c->y[b] ) + c->z[b];
			sum += ( c->across[0][i] + c->across[1][i] ) + c->across[2][i];
			c->table_edge[c->table_count++] = i;
		}
		c->run->sink += sum;
		return;
	}
	for ( int32_t i = e; i < end; ++i )
	{
		int32_t j = c->table_count++, b = c->edge_end[2 * i + 1];
		float pb[3];
		load3( c->x, c->y, c->z, b, pb );
		for ( int d = 0; d < 3; ++d )
		{
			c->table_lo[d][j] = pa[d] < pb[d] ? pa[d] : pb[d];
			c->table_hi[d][j] = pa[d] < pb[d] ? pb[d] : pa[d];
			lo[d] = c->table_lo[d][j] < lo[d] ? c->table_lo[d][j] : lo[d];
			hi[d] = c->table_hi[d][j] > hi[d] ? c->table_hi[d][j] : hi[d];
		}
		float u[3] = { pb[0] - pa[0], pb[1] - pa[1], pb[2] - pa[2] };
		float uu = u[0] * u[0] + u[1] * u[1] + u[2] * u[2];
		float iu = uu > 0.0f ? 1.0f / sqrtf( uu ) : 0.0f;
		for ( int d = 0; d < 3; ++d )
		{
			c->table_at[d][j] = pa[d];
			c->table_across[d][j] = c->across[d][i];
			c->table_along[d][j] = u[d] * iu;
		}
		/* b's projection by table_hits' own arithmetic, so that b itself is never beyond it */
		c->table_length[j] = u[0] * c->table_along[0][j] + u[1] * c->table_along[1][j] + u[2] * c->table_along[2][j];
		c->table_lower[j] = a, c->table_upper[j] = b, c->table_edge[j] = i;
	}
	float far[3];
	for ( int d = 0; d < 3; ++d )
	{
		far[d] = fabsf( lo[d] ) > fabsf( hi[d] ) ? fabsf( lo[d] ) : fabsf( hi[d] );
	}
	float r = cull_radius( thickness, far ) + c->grow;
	for ( int32_t j = from; j < c->table_count; ++j )
	{
		for ( int d = 0; d < 3; ++d )
		{
			c->table_lo[d][j] -= r, c->table_hi[d][j] += r;
		}
		c->table_margin[j] = r;
	}
	group->lo_x[k] = lo[0] - r, group->lo_y[k] = lo[1] - r, group->lo_z[k] = lo[2] - r;
	group->hi_x[k] = hi[0] + r, group->hi_y[k] = hi[1] + r, group->hi_z[k] = hi[2] + r;
}

/* Queries vertex block `block` for edge–edge pairs: groups of up to eight lanes, each standing
 * for up to LANE_EDGES of the edges a vertex is the lower end of, in vertex order (a vertex that is
 * no edge's lower end takes no lane). Non-finite positions are reported by the vertex–triangle
 * blocks. */
void sere_coll_detect_edge_block( detect_context* c, const sere_bvh* bvh, int32_t block, int32_t n, float thickness )
{
	int32_t a = block * DETECT_BLOCK, end = ( block + 1 ) * DETECT_BLOCK < n ? ( block + 1 ) * DETECT_BLOCK : n;
	int32_t e = c->lower_edge[a];
	for ( ;; )
	{
		sere_bvh_group group;
		group.count = 0;
		c->table_count = 0;
		while ( group.count < SERE_BVH_WIDTH && a < end )
		{
			int32_t last = c->lower_edge[a + 1];
			if ( e == last )
			{
				a += 1;
				e = c->lower_edge[a];
				continue;
			}
			int32_t stop = last - e > LANE_EDGES ? e + LANE_EDGES : last;
			if ( group.count == 0 )
			{
				c->first = a;
			}
			table_lane( c, &group, group.count++, a, e, stop, thickness );
			e = stop;
		}
		if ( group.count == 0 )
		{
			break;
		}
		c->table_lane[group.count] = c->table_count;
		/* detect_edge_visit keeps only edges whose lower end is above c->first, so whose upper
		 * end is above c->first + 1: a triangle with no corner above that owns none of them */
		if ( c->run != NULL )
		{
			sere_bvh_query_group_traced( bvh, &group, true, c->first + 1, &c->run->trace, detect_edge_visit, c );
		}
		else
		{
			sere_bvh_query_group_above( bvh, &group, c->first + 1, detect_edge_visit, c );
		}
		detect_edge_candidates( c );
	}
	sere_coll_detect_edge_flush( c );
}

/* The unit vector across edge e = (a, b) in the plane of its first triangle: n × (b − a),
 * normalized (zero when that is degenerate), for table_hits. */
void sere_coll_edge_across_at( sere_collide* collide, const int32_t* tri, const float* x, const float* y,
							   const float* z, int32_t e )
{
	float corner[3][3], n[3], pa[3], pb[3];
	triangle_frame( x, y, z, tri + 3 * (size_t) collide->edge_triangle[e], corner[0], corner[1], corner[2], n );
	load3( x, y, z, collide->edge_end[2 * e], pa );
	load3( x, y, z, collide->edge_end[2 * e + 1], pb );
	float u[3] = { pb[0] - pa[0], pb[1] - pa[1], pb[2] - pa[2] };
	float m[3] = { n[1] * u[2] - n[2] * u[1], n[2] * u[0] - n[0] * u[2], n[0] * u[1] - n[1] * u[0] };
	float length = sqrtf( m[0] * m[0] + m[1] * m[1] + m[2] * m[2] );
	float inverse = length > 0.0f ? 1.0f / length : 0.0f;
	size_t stride = (size_t) sere_pad( collide->edge_count );
	for ( int d = 0; d < 3; ++d )
	{
		collide->edge_across[(size_t) d * stride + (size_t) e] = m[d] * inverse;
	}
}

float sere_coll_edge_across_touch( sere_collide* collide, const int32_t* tri, const float* x, const float* y,
								   const float* z, int32_t e, float one )
{
	const int32_t* v = tri + 3 * (size_t) collide->edge_triangle[e];
	int32_t points[5] = { v[0], v[1], v[2], collide->edge_end[2 * e], collide->edge_end[2 * e + 1] };
	float sum = 0.0f;
	for ( int k = 0; k < 5; ++k )
	{
		sum += ( x[points[k]] + y[points[k]] ) + z[points[k]];
	}
	size_t stride = (size_t) sere_pad( collide->edge_count );
	for ( int d = 0; d < 3; ++d )
	{
		float* across = collide->edge_across + (size_t) d * stride + (size_t) e;
		*across = *across * one;
	}
	return sum;
}
