/* sere — the contact response: per contact the push along the normal to the thickness, shared between the contacts of a
 * vertex by Jacobi averaging, and the detect + respond rounds of sere_collide_resolve. _GNU_SOURCE: sched_getaffinity
 * for internal/team.h. */
#define _GNU_SOURCE

#include "solve/internal/collide_shared.h"

/* Gathers the four members' points of contacts [begin, begin + count) into rows 3r .. 3r + 2 of
 * point (x, y, z of member r), eight contacts at a time (sere_v8_gather_records). */
static void gather_members( const sere_collide* c, int32_t begin, int32_t count, float point[12][EVALUATE_BLOCK] )
{
	for ( int32_t m = 0; m < count; m += GATHER_LANES )
	{
		for ( int r = 0; r < 4; ++r )
		{
			const int32_t* index = c->member[r] + begin + m;
			int32_t tail[GATHER_LANES];
			if ( m + GATHER_LANES > count )
			{
				/* a short last batch repeats its last contact; the lanes past count are not used */
				for ( int l = 0; l < GATHER_LANES; ++l )
				{
					tail[l] = index[m + l < count ? l : count - 1 - m];
				}
				index = tail;
			}
			sere_v8_gather_records( c->position, index, point[3 * r] + m, point[3 * r + 1] + m, point[3 * r + 2] + m );
		}
	}
}

/* Writes the corrections of contacts [begin, begin + count), rows (λ n̂, push), to corr as
 * records. */
static void store_corrections( sere_collide* c, int32_t begin, int32_t count, float row[4][EVALUATE_BLOCK] )
{
	float* corr = c->corr + 4 * (size_t) begin;
	int32_t whole = count - count % GATHER_LANES;
	for ( int32_t m = 0; m < whole; m += GATHER_LANES )
	{
		sere_v8_scatter_records( row[0] + m, row[1] + m, row[2] + m, row[3] + m, corr + 4 * (size_t) m );
	}
	for ( int32_t k = whole; k < count; ++k )
	{
		corr[4 * k] = row[0][k], corr[4 * k + 1] = row[1][k], corr[4 * k + 2] = row[2][k], corr[4 * k + 3] = row[3][k];
	}
}

/* The response of contact k of an evaluation block, n its normal (not unit: scaled here by
 * side / |n| into n̂) and d the vector between its two points of detection: the height d · n̂
 * falls short of √(h² − |l|²), where the points are the thickness h apart for their lateral
 * offset l, by the deficit, and λ = deficit / W. Stores row column k = (λ n̂, 1) for a contact that pushes,
 * zeros for one that does not (a degenerate normal, scale 0, or an immovable contact, 1/W = 0,
 * never does); returns 1 when it pushes by more than the tolerance. */
static inline __attribute__( ( always_inline ) ) int32_t push_lane( float n[3], const float d[3], float side,
																	float inverse, float h2, float tolerance,
																	float row[4][EVALUATE_BLOCK], int32_t k )
{
	float length2 = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
	/* side is ±1, so side / |n| = side · (1 / |n|) exactly; written as a product used on every
	 * path, its load stays a plain vector load instead of a masked one */
	float inverse_length = length2 > 0.0f ? 1.0f / sqrtf( length2 > 0.0f ? length2 : 1.0f ) : 0.0f;
	float scale = side * inverse_length;
	n[0] *= scale, n[1] *= scale, n[2] *= scale;
	float height = d[0] * n[0] + d[1] * n[1] + d[2] * n[2];
	float l[3] = { d[0] - height * n[0], d[1] - height * n[1], d[2] - height * n[2] };
	float room = h2 - ( l[0] * l[0] + l[1] * l[1] + l[2] * l[2] );
	float deficit = sqrtf( room > 0.0f ? room : 0.0f ) - height;
	int push = ( room > 0.0f ) & ( deficit > 0.0f ) & ( scale != 0.0f ) & ( inverse > 0.0f );
	float lambda = push ? deficit * inverse : 0.0f;
	row[0][k] = lambda * n[0];
	row[1][k] = lambda * n[1];
	row[2][k] = lambda * n[2];
	row[3][k] = push ? 1.0f : 0.0f;
	return push & ( deficit > tolerance );
}

/* Evaluates vertex–triangle contacts [begin, end), at most EVALUATE_BLOCK of them, at the current
 * positions (see sere_collide_respond) at their points of detection q = u a + v b + w c, along
 * n = (b − a) × (c − a): stores corr[4k ..] = (λ n̂, 1) for a contact that pushes, zeros for one
 * that does not (push_lane), and returns how many push by more than the tolerance. The four
 * points are gathered first, then the arithmetic runs as straight-line vector code across
 * contacts. */
static int32_t evaluate_contacts( sere_collide* c, int32_t begin, int32_t end, float h2, float tolerance )
{
	float point[12][EVALUATE_BLOCK];
	int32_t count = end - begin;
	gather_members( c, begin, count, point );
	const float* restrict bu = c->weight[0] + begin, * restrict bv = c->weight[1] + begin, * restrict bw = c->weight[2] + begin;
	const float* restrict side = c->contact_side + begin, * restrict inv_weight = c->inv_weight + begin;
	/* the corrections as rows (λ n̂, push), written to corr as records below */
	float row[4][EVALUATE_BLOCK];
	int32_t far = 0;
#pragma omp simd reduction( + : far )
	for ( int32_t k = 0; k < count; ++k )
	{
		float p[3] = { point[0][k], point[1][k], point[2][k] };
		float a[3] = { point[3][k], point[4][k], point[5][k] };
		float b[3] = { point[6][k], point[7][k], point[8][k] };
		float cc[3] = { point[9][k], point[10][k], point[11][k] };
		float ab[3] = { b[0] - a[0], b[1] - a[1], b[2] - a[2] };
		float ac[3] = { cc[0] - a[0], cc[1] - a[1], cc[2] - a[2] };
		float n[3] = { ab[1] * ac[2] - ab[2] * ac[1], ab[2] * ac[0] - ab[0] * ac[2], ab[0] * ac[1] - ab[1] * ac[0] };
		float d[3];
		for ( int r = 0; r < 3; ++r )
		{
			d[r] = p[r] - ( bu[k] * a[r] + bv[k] * b[r] + bw[k] * cc[r] );
		}
		far += push_lane( n, d, side[k], inv_weight[k], h2, tolerance, row, k );
	}
	store_corrections( c, begin, count, row );
	return far;
}

/* evaluate_contacts for edge–edge contacts [begin, end): the same constraint between the points
 * of detection p = (1 − s) a0 + s a1 and q = (1 − t) b0 + t b1, along n = (a1 − a0) × (b1 − b0).
 * Parallel edges have no normal (scale 0) and never push. */
static int32_t evaluate_edges( sere_collide* c, int32_t begin, int32_t end, float h2, float tolerance )
{
	float point[12][EVALUATE_BLOCK];
	int32_t count = end - begin;
	gather_members( c, begin, count, point );
	const float* restrict ws = c->weight[0] + begin, * restrict wt = c->weight[1] + begin;
	const float* restrict side = c->contact_side + begin, * restrict inv_weight = c->inv_weight + begin;
	float row[4][EVALUATE_BLOCK];
	int32_t far = 0;
#pragma omp simd reduction( + : far )
	for ( int32_t k = 0; k < count; ++k )
	{
		float a0[3] = { point[0][k], point[1][k], point[2][k] };
		float a1[3] = { point[3][k], point[4][k], point[5][k] };
		float b0[3] = { point[6][k], point[7][k], point[8][k] };
		float b1[3] = { point[9][k], point[10][k], point[11][k] };
		float u[3] = { a1[0] - a0[0], a1[1] - a0[1], a1[2] - a0[2] };
		float v[3] = { b1[0] - b0[0], b1[1] - b0[1], b1[2] - b0[2] };
		float n[3] = { u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0] };
		float s = ws[k], t = wt[k];
		float d[3];
		for ( int r = 0; r < 3; ++r )
		{
			d[r] = ( ( 1.0f - s ) * a0[r] + s * a1[r] ) - ( ( 1.0f - t ) * b0[r] + t * b1[r] );
		}
		far += push_lane( n, d, side[k], inv_weight[k], h2, tolerance, row, k );
	}
	store_corrections( c, begin, count, row );
	return far;
}

/* The floor's evaluate_contacts or evaluate_edges (vertex false): their gathers and loads (three
 * weights of a vertex–triangle contact, two of an edge–edge one), with their sums stored for the
 * corrections and, for the push, the flag the recorded evaluation stored (flags: a bit a contact). */
static void touch_evaluate( sere_collide* c, int32_t begin, int32_t end, bool vertex, const uint8_t* flags )
{
	float point[12][EVALUATE_BLOCK];
	int32_t count = end - begin;
	gather_members( c, begin, count, point );
	float row[4][EVALUATE_BLOCK];
	for ( int32_t k = 0; k < count; ++k )
	{
		int32_t at = begin + k;
		float loads = ( ( c->weight[0][at] + c->weight[1][at] ) + ( vertex ? c->weight[2][at] : 0.0f ) ) +
					  ( c->contact_side[at] + c->inv_weight[at] );
		for ( int r = 0; r < 3; ++r )
		{
			row[r][k] = ( ( point[r][k] + point[3 + r][k] ) + ( point[6 + r][k] + point[9 + r][k] ) ) + loads;
		}
		row[3][k] = (float) ( flags[k / 8] >> ( k % 8 ) & 1u );
	}
	store_corrections( c, begin, count, row );
}

/* Recording a served pass: the push flags contacts [begin, end) were stored with. */
static void record_pushes( const sere_collide* c, int32_t begin, int32_t end, uint8_t* flags )
{
	memset( flags, 0, PUSH_BYTES );
	for ( int32_t k = begin; k < end; ++k )
	{
		flags[( k - begin ) / 8] |= (uint8_t) ( ( c->corr[4 * (size_t) k + 3] != 0.0f ) << ( ( k - begin ) % 8 ) );
	}
}

/* The coefficient of entry e as a group (coefficient, coefficient, coefficient, 1), or for the
 * floor (touch) with 0 in lane 3: it adds the group to the correction, whose lane 3 then still
 * sums to the count of pushing contacts gather_move tests. */
static inline sere_v4 entry_coefficient( const sere_collide* c, int32_t e, bool touch )
{
	return sere_v4_xyz( c->entry_coef[e], touch ? 0.0f : 1.0f );
}

/* The correction record of entry e. */
static inline sere_v4 entry_correction( const sere_collide* c, int32_t e )
{
	return sere_v4_load( c->corr + 4 * (size_t) c->entries[e] );
}

/* Adds the entries [e, end) to sum in order (their products, or for the floor their sums). */
static inline sere_v4 gather_sum( const sere_collide* c, int32_t e, int32_t end, sere_v4 sum, bool touch )
{
	for ( ; e < end; ++e )
	{
		sere_v4 coefficient = entry_coefficient( c, e, touch ), corr = entry_correction( c, e );
		sum = sere_v4_add( sum, touch ? sere_v4_add( coefficient, corr ) : sere_v4_mul( coefficient, corr ) );
	}
	return sum;
}

/* Moves touched vertex slot j (vertex i) by ω / count times the summed correction. The floor
 * (touch) adds where this multiplies and stores the position as it is (times one). */
static inline void gather_move( sere_collide* c, int32_t j, sere_v4 sum, const float* inv_m, float relaxation,
								bool touch, float one )
{
	int32_t i = c->touched[j];
	if ( sere_v4_w( sum ) == 0.0f )
	{
		return;
	}
	float scale = touch ? relaxation + inv_m[i] : relaxation * inv_m[i];
	/* lane 3 scaled by 0: the padding stays 0 (the floor's moves keep the count there; their
	 * padding is never read) */
	sere_v4 d = touch ? sere_v4_add( sum, sere_v4_xyz( scale, 0.0f ) ) : sere_v4_mul( sum, sere_v4_xyz( scale, 0.0f ) );
	float* position = c->position + 4 * (size_t) i;
	float* acc = c->acc + 4 * (size_t) j;
	sere_v4 at = sere_v4_load( position );
	sere_v4_store( position, touch ? sere_v4_mul( at, sere_v4_xyz( one, one ) ) : sere_v4_add( at, d ) );
	sere_v4_store( acc, sere_v4_add( sere_v4_load( acc ), d ) );
}

/* Moves touched vertex slots j and j + 1 (gather_apply for each), their sums side by side in
 * one group of eight while both have entries left, then each on its own: every lane sees the
 * products and sums of the one-vertex form in the same order. A vertex averages 21 entries on
 * the dried maple, and two independent chains of adds keep the adder busy where one waits on
 * the last add. */
static inline void gather_apply_pair( sere_collide* c, int32_t j, const float* inv_m, float relaxation, bool touch,
									  float one )
{
	int32_t i0 = c->touched[j], i1 = c->touched[j + 1];
	int32_t e0 = c->entry_offset[i0], end0 = c->entry_offset[i0 + 1];
	int32_t e1 = c->entry_offset[i1], end1 = c->entry_offset[i1 + 1];
	int32_t common = end0 - e0 < end1 - e1 ? end0 - e0 : end1 - e1;
	sere_v8 sum = sere_v8_zero();
	for ( int32_t k = 0; k < common; ++k )
	{
		sere_v8 coefficient =
			sere_v8_pair( entry_coefficient( c, e0 + k, touch ), entry_coefficient( c, e1 + k, touch ) );
		sere_v8 corr = sere_v8_pair( entry_correction( c, e0 + k ), entry_correction( c, e1 + k ) );
		sum = sere_v8_add( sum, touch ? sere_v8_add( coefficient, corr ) : sere_v8_mul( coefficient, corr ) );
	}
	sere_v4 sum0 = gather_sum( c, e0 + common, end0, sere_v8_low( sum ), touch );
	sere_v4 sum1 = gather_sum( c, e1 + common, end1, sere_v8_high( sum ), touch );
	gather_move( c, j, sum0, inv_m, relaxation, touch, one );
	gather_move( c, j + 1, sum1, inv_m, relaxation, touch, one );
}

/* Moves touched vertex slot j by ω times the mean of its pushing contacts' corrections, summed
 * in contact order (a contact that does not push has a zero correction and counts 0). The sums
 * run in the four lanes of one group, (coefficient, coefficient, coefficient, 1) times the
 * contact's (λ n̂, 1). */
static inline void gather_apply( sere_collide* c, int32_t j, const float* inv_m, float relaxation, bool touch,
								 float one )
{
	int32_t i = c->touched[j];
	sere_v4 sum = gather_sum( c, c->entry_offset[i], c->entry_offset[i + 1], sere_v4_zero(), touch );
	gather_move( c, j, sum, inv_m, relaxation, touch, one );
}

/* Moves the touched slots [begin, end), two at a time (gather_apply_pair), then the last; inlined
 * with a constant touch, so the response and its floor each get their own loop. */
static inline __attribute__( ( always_inline ) ) void gather_run( sere_collide* c, int32_t begin, int32_t end,
																  const float* inv_m, float relaxation, bool touch,
																  float one )
{
	int32_t j = begin;
	for ( ; j + 1 < end; j += 2 )
	{
		gather_apply_pair( c, j, inv_m, relaxation, touch, one );
	}
	if ( j < end )
	{
		gather_apply( c, j, inv_m, relaxation, touch, one );
	}
}

/* The first touched slot of part `part` of `parts` when the touched vertices are cut into runs
 * of about equal gather work (entries): vertices differ a lot in their number of contacts (on the
 * dried maple one half of the touched vertices holds 62% of the entries), and a cut by vertex
 * count would leave one thread waiting at every iteration's barrier. */
/* Averaging without creating momentum. A vertex in n pushing contacts must not take the sum of
 * their corrections (Jacobi overshoots), but dividing each vertex's sum by its own n (Macklin
 * et al. 2014) gives the members of one contact different shares of its impulse, and the leaf's
 * centre of mass moves: 0.009 L over a green maple's run, all of it in the frames with edge
 * contacts. Instead each contact's correction is divided by the largest n among its four
 * members, so all of them take the same share and Σ m Δx = λ n̂ Σ coefficients = 0 per contact
 * (the coefficients 1, −u, −v, −w or 1 − s, s, −(1 − t), −t sum to 0). Called by every thread of
 * the response between the evaluation and the gather: counts for its touched vertices, a
 * barrier, then the shares for its contacts (the loop's own barrier ends it). */
static void share_pushes( sere_collide* c, int32_t mine_begin, int32_t mine_end, int32_t contacts, bool touch )
{
	for ( int32_t j = mine_begin; j < mine_end; ++j )
	{
		int32_t i = c->touched[j];
		float n = 0.0f;
		for ( int32_t e = c->entry_offset[i]; e < c->entry_offset[i + 1]; ++e )
		{
			n += c->corr[4 * (size_t) c->entries[e] + 3];
		}
		c->push_count[i] = n;
	}
#pragma omp barrier
#pragma omp for schedule( static )
	for ( int32_t k = 0; k < contacts; ++k )
	{
		float* corr = c->corr + 4 * (size_t) k;
		if ( corr[3] == 0.0f )
		{
			continue;
		}
		/* the floor (touch) adds the counts and the share in place of the maximum, division and
		 * products */
		float n = 1.0f;
		for ( int r = 0; r < 4; ++r )
		{
			float count = c->push_count[c->member[r][k]];
			n = touch ? n + count : fmaxf( n, count );
		}
		float share = touch ? n : 1.0f / n;
		for ( int r = 0; r < 3; ++r )
		{
			corr[r] = touch ? corr[r] + share : corr[r] * share;
		}
	}
}

static int32_t touched_split( const sere_collide* c, int part, int parts )
{
	if ( part >= parts )
	{
		return c->touched_count;
	}
	int64_t target = (int64_t) c->entry_offset[c->vertex_count] * part / parts;
	int32_t lo = 0, hi = c->touched_count;
	while ( lo < hi )
	{
		int32_t mid = lo + ( hi - lo ) / 2;
		if ( c->entry_offset[c->touched[mid]] < target )
		{
			lo = mid + 1;
		}
		else
		{
			hi = mid;
		}
	}
	return lo;
}

static bool state_valid( const sere_collide_state* s )
{
	return s != NULL && s->x && s->y && s->z && s->vx && s->vy && s->vz && s->inv_m &&
		   ( s->x0 == NULL ) == ( s->y0 == NULL ) && ( s->x0 == NULL ) == ( s->z0 == NULL );
}

/* The side of contact k's triangle its vertex was on at the start of the step: the sign of
 * (p₀ − q₀) · n₀ at the detection weights, or the detection side when that is neither positive
 * nor negative (the vertex in the plane, a degenerate triangle, or NaN, which respond refuses).
 * For an edge–edge contact (vertex false), the side of its second edge the first was on: the same
 * sign with p₀, q₀ the points of detection on the two edges and n₀ = (a1 − a0) × (b1 − b0). */
static inline float history_side( const sere_collide* c, const sere_collide_state* s, int32_t k, bool vertex )
{
	float point[4][3];
	for ( int r = 0; r < 4; ++r )
	{
		load3( s->x0, s->y0, s->z0, c->member[r][k], point[r] );
	}
	float u = c->weight[0][k], v = c->weight[1][k], w = c->weight[2][k];
	float ab[3], ac[3], d[3];
	for ( int r = 0; r < 3; ++r )
	{
		if ( vertex )
		{
			ab[r] = point[2][r] - point[1][r], ac[r] = point[3][r] - point[1][r];
			d[r] = point[0][r] - ( u * point[1][r] + v * point[2][r] + w * point[3][r] );
		}
		else
		{
			ab[r] = point[1][r] - point[0][r], ac[r] = point[3][r] - point[2][r];
			d[r] = ( ( 1.0f - u ) * point[0][r] + u * point[1][r] ) - ( ( 1.0f - v ) * point[2][r] + v * point[3][r] );
		}
	}
	float n[3] = { ab[1] * ac[2] - ab[2] * ac[1], ab[2] * ac[0] - ab[0] * ac[2], ab[0] * ac[1] - ab[1] * ac[0] };
	float height = d[0] * n[0] + d[1] * n[1] + d[2] * n[2];
	return height > 0.0f ? 1.0f : ( height < 0.0f ? -1.0f : c->contact_side[k] );
}

/* The floor's history_side: its loads, added up (the side it finds is the one already there). */
static inline float history_loads( const sere_collide* c, const sere_collide_state* s, int32_t k )
{
	float sum = ( c->weight[0][k] + c->weight[1][k] ) + c->weight[2][k];
	for ( int r = 0; r < 4; ++r )
	{
		int32_t m = c->member[r][k];
		sum += ( s->x0[m] + s->y0[m] ) + s->z0[m];
	}
	return sum;
}

static bool params_valid( const sere_collide_params* p )
{
	return p != NULL && p->thickness > 0.0f && isfinite( p->thickness ) && p->dt > 0.0f && isfinite( p->dt ) &&
		   p->iterations >= 0 && p->rounds >= 1 && p->rebuild_ratio > 0.0 && p->relaxation > 0.0f &&
		   p->relaxation <= 2.0f;
}

/* Loads the touched vertices' positions into records (checking the inputs the response reads)
 * and zeroes their accumulated moves; W = w_p + Σ w_k b_k² (or Σ over the edge ends of w times the
 * squared weight on the edge) with the weights of detection, fixed for the response. Nonzero when
 * an input is not finite. The floor (touch) adds up what the checks load, into *sink, and the
 * loads of W into its place. */
static int load_response( sere_collide* collide, const sere_collide_state* state, int32_t vertex_contacts,
						  int32_t contacts, bool parallel, bool touch, float* sink )
{
	int32_t touched = collide->touched_count;
	const float* inv_m = state->inv_m;
	int bad = 0;
	float sum = 0.0f;
#pragma omp parallel num_threads( sere_team_for( collide->threads ) ) if ( parallel )
	{
#pragma omp for reduction( | : bad ) reduction( + : sum ) schedule( static ) nowait
		for ( int32_t j = 0; j < touched; ++j )
		{
			int32_t i = collide->touched[j];
			if ( touch )
			{
				sum += ( ( state->vx[i] + state->vy[i] ) + ( state->vz[i] + inv_m[i] ) ) +
					   ( state->x0 != NULL ? ( state->x0[i] + state->y0[i] ) + state->z0[i] : 0.0f );
			}
			else
			{
				bad |= !( isfinite( state->vx[i] ) && isfinite( state->vy[i] ) && isfinite( state->vz[i] ) &&
						  isfinite( inv_m[i] ) && inv_m[i] >= 0.0f );
				bad |= state->x0 != NULL &&
					   !( isfinite( state->x0[i] ) && isfinite( state->y0[i] ) && isfinite( state->z0[i] ) );
			}
			float* position = collide->position + 4 * (size_t) i;
			position[0] = state->x[i], position[1] = state->y[i], position[2] = state->z[i], position[3] = 0.0f;
			float* acc = collide->acc + 4 * (size_t) j;
			acc[0] = acc[1] = acc[2] = acc[3] = 0.0f;
		}
#pragma omp for schedule( static )
		for ( int32_t k = 0; k < contacts; ++k )
		{
			int32_t* const* m = collide->member;
			float u = collide->weight[0][k], v = collide->weight[1][k], w = collide->weight[2][k];
			if ( touch )
			{
				collide->inv_weight[k] =
					( ( inv_m[m[0][k]] + inv_m[m[1][k]] ) + ( inv_m[m[2][k]] + inv_m[m[3][k]] ) ) + ( ( u + v ) + w );
				continue;
			}
			float weight =
				k < vertex_contacts
					? inv_m[m[0][k]] + inv_m[m[1][k]] * u * u + inv_m[m[2][k]] * v * v + inv_m[m[3][k]] * w * w
					: inv_m[m[0][k]] * ( 1.0f - u ) * ( 1.0f - u ) + inv_m[m[1][k]] * u * u +
						  inv_m[m[2][k]] * ( 1.0f - v ) * ( 1.0f - v ) + inv_m[m[3][k]] * v * v;
			collide->inv_weight[k] = weight > 0.0f ? 1.0f / weight : 0.0f;
		}
	}
	*sink += sum;
	return bad;
}

/* Evaluates the calling thread's share of the evaluation blocks (a static share: a worksharing
 * loop inside the caller's parallel region) and returns how many of its contacts push by more
 * than the tolerance. With pushes (a served pass's record, this evaluation's flags), records each
 * block's push flags, or the floor (touch) evaluates by them (touch_evaluate) and returns 0. */
static int32_t evaluate_share( sere_collide* collide, int32_t blocks, int32_t vertex_blocks, int32_t contacts, float h2,
							   float tolerance, uint8_t* pushes, bool touch )
{
	int32_t vertex_contacts = collide->contact_count;
	int32_t mine = 0;
#pragma omp for schedule( static ) nowait
	for ( int32_t block = 0; block < blocks; ++block )
	{
		bool vertex = block < vertex_blocks;
		int32_t begin = vertex ? block * EVALUATE_BLOCK : vertex_contacts + ( block - vertex_blocks ) * EVALUATE_BLOCK;
		int32_t last = vertex ? vertex_contacts : contacts;
		int32_t end = begin + EVALUATE_BLOCK < last ? begin + EVALUATE_BLOCK : last;
		uint8_t* flags = pushes != NULL ? pushes + (size_t) block * PUSH_BYTES : NULL;
		if ( touch )
		{
			touch_evaluate( collide, begin, end, vertex, flags );
			continue;
		}
		mine += vertex ? evaluate_contacts( collide, begin, end, h2, tolerance )
					   : evaluate_edges( collide, begin, end, h2, tolerance );
		if ( flags != NULL )
		{
			record_pushes( collide, begin, end, flags );
		}
	}
	return mine;
}

/* Writes the touched slots [begin, end) back: the moved positions, and velocities changed by the
 * accumulated move over dt. The floor (touch) stores the velocities as they are (times one) and
 * returns the sum of the moves it loads (0 otherwise). */
static float write_back( const sere_collide* collide, const sere_collide_state* state, int32_t begin, int32_t end,
						 float inv_dt, bool touch, float one )
{
	float sum = 0.0f;
	for ( int32_t j = begin; j < end; ++j )
	{
		int32_t i = collide->touched[j];
		const float* position = collide->position + 4 * (size_t) i;
		const float* acc = collide->acc + 4 * (size_t) j;
		state->x[i] = position[0], state->y[i] = position[1], state->z[i] = position[2];
		if ( touch )
		{
			sum += ( acc[0] + acc[1] ) + acc[2];
			state->vx[i] *= one, state->vy[i] *= one, state->vz[i] *= one;
			continue;
		}
		state->vx[i] += acc[0] * inv_dt;
		state->vy[i] += acc[1] * inv_dt;
		state->vz[i] += acc[2] * inv_dt;
	}
	return sum;
}

/* The response; with a record (sere_collide_record_served), also recording what each evaluation
 * pushed, or, touch, the floor of the recorded response (sere_collide_touch_served): its passes
 * for the evaluations it ran, with the pushes read from the record. */
static sere_status respond( sere_collide* collide, const sere_bvh* bvh, const sere_collide_state* state,
							const sere_collide_params* params, collide_record* record, bool touch, int32_t* unresolved,
							int32_t* iterations )
{
	if ( collide == NULL || bvh == NULL || !state_valid( state ) || !params_valid( params ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	int32_t triangles;
	sere_bvh_triangles( bvh, &triangles );
	if ( triangles != collide->triangle_count || sere_bvh_vertex_count( bvh ) != collide->vertex_count )
	{
		return SERE_ERR_ARGUMENT;
	}
	/* the vertex–triangle contacts [0, vertex_contacts), then the edge–edge ones */
	int32_t vertex_contacts = collide->contact_count;
	int32_t contacts = vertex_contacts + collide->edge_contact_count;
	/* A few hundred contacts take less time than the barriers of a parallel response; the result
	 * is the same either way. */
	bool parallel = contacts >= RESPOND_PARALLEL;
	const float* inv_m = state->inv_m;
	float loads = 0.0f, one = record != NULL ? record->one : 1.0f;
	int bad = load_response( collide, state, vertex_contacts, contacts, parallel, touch, &loads );
	if ( bad )
	{
		return SERE_ERR_NONFINITE;
	}
	float h = params->thickness, h2 = h * h;
	float tolerance = SERE_COLLIDE_TOLERANCE * h;
	float inv_dt = 1.0f / params->dt;
	/* evaluation blocks of each kind, the edge–edge ones after the others */
	int32_t vertex_blocks = ( vertex_contacts + EVALUATE_BLOCK - 1 ) / EVALUATE_BLOCK;
	int32_t blocks = vertex_blocks + ( contacts - vertex_contacts + EVALUATE_BLOCK - 1 ) / EVALUATE_BLOCK;
	/* the floor's last evaluation is the recorded one's */
	int32_t last = touch ? record->evaluations - 1 : params->iterations;
	int32_t remaining = 0, applied = 0;
	int32_t* far = collide->far_count;
	int threads = sere_team_for( collide->threads );
	threads = threads < collide->slots ? threads : collide->slots;
	/* Per-thread counts of contacts still short of the tolerance, summed by every thread after
	 * a barrier: two barriers per iteration (this one and the gather's), no reduction clause. */
#pragma omp parallel num_threads( threads ) if ( parallel )
	{
		int tid = omp_get_thread_num(), team = omp_get_num_threads();
		float sink = 0.0f; /* the floor's sums of what it loads */
		int32_t mine_begin = touched_split( collide, tid, team ), mine_end = touched_split( collide, tid + 1, team );
		/* the sides, only now that every input is known to be finite (an error leaves them) */
		if ( state->x0 != NULL )
		{
#pragma omp for schedule( static )
			for ( int32_t k = 0; k < contacts; ++k )
			{
				bool vertex = k < vertex_contacts;
				float side = touch ? collide->contact_side[k] * one : history_side( collide, state, k, vertex );
				sink += touch ? history_loads( collide, state, k ) : 0.0f;
				collide->contact_side[k] = side;
				*( vertex ? &collide->contacts[k].side : &collide->edge_contacts[k - vertex_contacts].side ) = side;
			}
		}
		for ( int32_t it = 0; it <= last; ++it )
		{
			uint8_t* pushes =
				record != NULL ? record->pushes + (size_t) it * (size_t) blocks * (size_t) PUSH_BYTES : NULL;
			int32_t mine = evaluate_share( collide, blocks, vertex_blocks, contacts, h2, tolerance, pushes, touch );
			far[tid * FAR_STRIDE] = mine;
#pragma omp barrier
			int32_t total = 0;
			for ( int t = 0; t < team; ++t )
			{
				total += far[t * FAR_STRIDE];
			}
			/* every contact within the tolerance, or the iterations spent (the last evaluation
			 * only counts what is left): the same decision on every thread */
			if ( ( total == 0 && !touch ) || it == last )
			{
#pragma omp single nowait
				remaining = total;
				break;
			}
			share_pushes( collide, mine_begin, mine_end, contacts, touch );
			if ( touch )
			{
				gather_run( collide, mine_begin, mine_end, inv_m, params->relaxation, true, one );
			}
			else
			{
				gather_run( collide, mine_begin, mine_end, inv_m, params->relaxation, false, one );
			}
			/* also keeps far[] from being rewritten before all have read it */
#pragma omp barrier
#pragma omp single nowait
			applied += 1;
		}
		/* the gather's share: each thread reads the sums it wrote */
		sink += write_back( collide, state, mine_begin, mine_end, inv_dt, touch, one );
		if ( touch )
		{
#pragma omp atomic
			record->sink += sink;
		}
	}
	if ( touch )
	{
		record->sink += loads;
	}
	*unresolved = remaining;
	*iterations = applied;
	return SERE_OK;
}

sere_status sere_collide_respond( sere_collide* collide, const sere_bvh* bvh, const sere_collide_state* state,
								  const sere_collide_params* params, int32_t* unresolved )
{
	int32_t remaining, iterations;
	sere_status status = respond( collide, bvh, state, params, NULL, false, &remaining, &iterations );
	if ( status == SERE_OK && unresolved != NULL )
	{
		*unresolved = remaining;
	}
	return status;
}

sere_status sere_collide_resolve( sere_collide* collide, sere_bvh* bvh, const sere_collide_state* state,
								  const sere_collide_params* params, sere_collide_stats* stats )
{
	if ( collide == NULL || bvh == NULL || !state_valid( state ) || !params_valid( params ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	sere_collide_stats local = { 0 };
	/* A detection the candidate list serves does not read the tree: its refit (an O(n) pass,
	 * about 6% of the Table 1 maple's collision time at 1 thread) waits for the next search. */
	int served = sere_coll_list_serves( collide, bvh, state->x, state->y, state->z, params->thickness );
	sere_status status = SERE_OK;
	if ( !served )
	{
		status = sere_bvh_update( bvh, state->x, state->y, state->z, params->rebuild_ratio, &local.rebuilt );
	}
	for ( int32_t round = 0; status == SERE_OK && round < params->rounds; ++round )
	{
		if ( round > 0 )
		{
			status = sere_bvh_refit( bvh, state->x, state->y, state->z );
			if ( status != SERE_OK )
			{
				break;
			}
			served = -1;
		}
		int32_t found = 0;
		status = sere_coll_detect( collide, bvh, state->x, state->y, state->z, params->thickness, served, &found );
		if ( round == 0 )
		{
			local.contacts = found;
			local.edge_contacts = collide->edge_found < INT32_MAX ? (int32_t) collide->edge_found : INT32_MAX;
		}
		if ( status != SERE_OK )
		{
			break;
		}
		local.rounds += 1;
		local.unresolved = 0;
		if ( found == 0 && collide->edge_contact_count == 0 )
		{
			break;
		}
		int32_t iterations = 0;
		status = respond( collide, bvh, state, params, NULL, false, &local.unresolved, &iterations );
		local.iterations += iterations;
	}
	if ( stats != NULL )
	{
		*stats = local;
	}
	return status;
}

/* The response's part of a served pass's traffic over `evaluations` evaluations: every contact at
 * each, every gather entry at each but the last. */
static void response_traffic( const sere_collide* collide, int32_t evaluations, sere_collide_traffic* traffic )
{
	traffic->evaluated = ( (int64_t) collide->contact_count + collide->edge_contact_count ) * evaluations;
	traffic->gathered =
		evaluations > 0 ? (int64_t) collide->entry_offset[collide->vertex_count] * ( evaluations - 1 ) : 0;
}

sere_status sere_collide_record_served( sere_collide* collide, const sere_bvh* bvh, const sere_collide_state* state,
										const sere_collide_params* params, sere_collide_traffic* traffic )
{
	if ( collide == NULL || bvh == NULL || !state_valid( state ) || !params_valid( params ) || params->rounds != 1 ||
		 !sere_coll_list_serves( collide, bvh, state->x, state->y, state->z, params->thickness ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	/* the record, with room for every evaluation's push flags of as many contacts as the capacity
	 * holds, before the pass changes anything */
	if ( collide->record == NULL && ( collide->record = sere_alloc( sizeof( collide_record ) ) ) == NULL )
	{
		return SERE_ERR_MEMORY;
	}
	collide_record* record = collide->record;
	size_t blocks = 2 * (size_t) ( ( collide->capacity + EVALUATE_BLOCK - 1 ) / EVALUATE_BLOCK );
	size_t bytes = ( (size_t) params->iterations + 1 ) * blocks * PUSH_BYTES;
	if ( record->push_capacity < bytes )
	{
		record->valid = false;
		sere_free( record->pushes );
		record->pushes = sere_alloc( bytes );
		record->push_capacity = record->pushes != NULL ? bytes : 0;
		if ( record->pushes == NULL )
		{
			return SERE_ERR_MEMORY;
		}
	}
	sere_collide_traffic moved;
	sere_status status =
		sere_coll_record_detect( collide, bvh, state->x, state->y, state->z, params->thickness, 1, &moved );
	if ( status == SERE_OK && collide->contact_count + collide->edge_contact_count > 0 )
	{
		int32_t unresolved, applied;
		status = respond( collide, bvh, state, params, record, false, &unresolved, &applied );
		record->evaluations = applied + 1;
	}
	record->valid = record->valid && status == SERE_OK;
	record->params = *params;
	if ( status == SERE_OK && traffic != NULL )
	{
		response_traffic( collide, record->evaluations, &moved );
		*traffic = moved;
	}
	return status;
}

sere_status sere_collide_touch_served( sere_collide* collide, const sere_bvh* bvh, const sere_collide_state* state,
									   sere_collide_traffic* traffic )
{
	if ( !state_valid( state ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	sere_collide_traffic moved;
	sere_status status = sere_coll_touch_detect( collide, bvh, state->x, state->y, state->z, true, &moved );
	int32_t evaluations = 0;
	if ( status == SERE_OK && collide->record->evaluations > 0 )
	{
		int32_t unresolved, applied;
		status = respond( collide, bvh, state, &collide->record->params, collide->record, true, &unresolved, &applied );
		evaluations = applied + 1;
	}
	if ( status == SERE_OK && traffic != NULL )
	{
		response_traffic( collide, evaluations, &moved );
		*traffic = moved;
	}
	return status;
}
