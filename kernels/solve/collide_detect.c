/* sere — sere_collide_detect: the runs of blocks per thread, the candidate list (search or replay, see SKIN) and the
 * contact lists in block order. _GNU_SOURCE: sched_getaffinity for internal/team.h. */
#define _GNU_SOURCE

#include "solve/internal/collide_shared.h"

/* The first block of run `part` of `parts`: runs of about equal work (work_prefix: the blocks'
 * listed pairs for a served detection, the last search's times for a search), or of equal block
 * counts before any. */
static int32_t run_begin( const sere_collide* c, int part, int parts )
{
	if ( part >= parts )
	{
		return c->block_count;
	}
	int64_t total = c->work_prefix[c->block_count];
	if ( total == 0 )
	{
		return (int32_t) ( (int64_t) c->block_count * part / parts );
	}
	int64_t target = total * part / parts;
	int32_t lo = 0, hi = c->block_count;
	while ( lo < hi )
	{
		int32_t mid = lo + ( hi - lo ) / 2;
		if ( c->work_prefix[mid] < target )
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

/* Copies block `block`'s contacts, [begin, next) of the combined numbering (vertex–triangle
 * contacts first, total of them), into their list, and their members, sides and weights into the
 * per-contact arrays of the response. */
static void copy_block( sere_collide* c, const int32_t* tri, int32_t block, int64_t begin, int64_t next, int64_t total )
{
	size_t count = (size_t) ( next - begin );
	if ( block < c->vertex_blocks )
	{
		const sere_contact* from = thread_buffer( c, c->block_thread[block] ) + c->block_start[block];
		if ( count > 0 && from != c->contacts + begin )
		{
			memcpy( c->contacts + begin, from, sizeof( sere_contact ) * count );
		}
		for ( int64_t k = begin; k < next; ++k )
		{
			const sere_contact* contact = c->contacts + k;
			const int32_t* v = tri + 3 * (size_t) contact->triangle;
			c->member[0][k] = contact->vertex;
			c->member[1][k] = v[0], c->member[2][k] = v[1], c->member[3][k] = v[2];
			c->contact_side[k] = contact->side;
			c->weight[0][k] = contact->u, c->weight[1][k] = contact->v, c->weight[2][k] = contact->w;
		}
	}
	else
	{
		const sere_edge_contact* from = thread_edge_buffer( c, c->block_thread[block] ) + c->block_start[block];
		if ( count > 0 )
		{
			memcpy( c->edge_contacts + ( begin - total ), from, sizeof( sere_edge_contact ) * count );
		}
		for ( int64_t k = begin; k < next; ++k )
		{
			const sere_edge_contact* contact = c->edge_contacts + ( k - total );
			c->member[0][k] = contact->a0, c->member[1][k] = contact->a1;
			c->member[2][k] = contact->b0, c->member[3][k] = contact->b1;
			c->contact_side[k] = contact->side;
			c->weight[0][k] = contact->s, c->weight[1][k] = contact->t, c->weight[2][k] = 0.0f;
		}
	}
}

/* Lists the contacts found (total vertex–triangle ones, then edge_total edge–edge ones): copies
 * each block's contacts from its thread's buffer to the block's place in its list (thread 0's
 * vertex–triangle contacts are there already), with the per-contact arrays of the response, and
 * builds the per-vertex gather lists by a stable counting sort, in one parallel region. Each
 * thread counts the entries of its own (static, contiguous) share of blocks per vertex; then,
 * over its run of vertices, turns the counts of every thread into where each thread's entries of
 * each vertex begin, thread by thread: a vertex's list is then in contact order whatever the
 * thread count. Each thread finally writes the entries of the contacts it copied. Run
 * sequentially, the gather lists alone cost a fifth of the search's time on two threads (random
 * writes into a list of 4 × contacts entries). */
static void list_contacts( sere_collide* c, const int32_t* tri, int64_t total, int64_t edge_total, int threads )
{
	int32_t n = c->vertex_count;
	size_t stride = (size_t) sere_pad( n );
	int64_t all = total + edge_total;
#pragma omp parallel num_threads( threads )
	{
		int tid = omp_get_thread_num(), team = omp_get_num_threads();
		int32_t* mine = c->entry_cursor + (size_t) tid * stride;
		memset( mine, 0, sizeof( int32_t ) * (size_t) n );
#pragma omp for schedule( static )
		for ( int32_t block = 0; block < c->block_count; ++block )
		{
			int64_t begin = c->block_found[block];
			int64_t next = block + 1 < c->block_count ? c->block_found[block + 1] : all;
			copy_block( c, tri, block, begin, next, total );
			for ( int64_t k = begin; k < next; ++k )
			{
				for ( int r = 0; r < 4; ++r )
				{
					mine[c->member[r][k]] += 1;
				}
			}
		}
		/* this thread's run of vertices: its entries and touched vertices */
		int32_t first, last;
		sere_team_share( 0, n, tid, team, &first, &last );
		int32_t entries = 0, touched = 0;
		for ( int32_t i = first; i < last; ++i )
		{
			int32_t before = entries;
			for ( int t = 0; t < team; ++t )
			{
				entries += c->entry_cursor[(size_t) t * stride + (size_t) i];
			}
			touched += entries > before;
		}
		c->run_total[2 * FAR_STRIDE * tid] = entries;
		c->run_total[2 * FAR_STRIDE * tid + 1] = touched;
#pragma omp barrier
		entries = touched = 0;
		for ( int t = 0; t < tid; ++t )
		{
			entries += c->run_total[2 * FAR_STRIDE * t];
			touched += c->run_total[2 * FAR_STRIDE * t + 1];
		}
		for ( int32_t i = first; i < last; ++i )
		{
			c->entry_offset[i] = entries;
			for ( int t = 0; t < team; ++t )
			{
				int32_t* cursor = c->entry_cursor + (size_t) t * stride + (size_t) i;
				int32_t count = *cursor;
				*cursor = entries;
				entries += count;
			}
			if ( entries > c->entry_offset[i] )
			{
				c->touched[touched++] = i;
			}
		}
		if ( tid == team - 1 )
		{
			c->entry_offset[n] = entries;
			c->touched_count = touched;
		}
#pragma omp barrier
		/* the same static schedule as the copy: each thread lists the contacts it counted */
#pragma omp for schedule( static )
		for ( int32_t block = 0; block < c->block_count; ++block )
		{
			int64_t next = block + 1 < c->block_count ? c->block_found[block + 1] : all;
			for ( int64_t k = c->block_found[block]; k < next; ++k )
			{
				/* a triangle's corners move against the push by their barycentric weight, the
				 * vertex with it; the first edge's ends with it by their weights on the edge, the
				 * second edge's against it */
				bool vertex = k < total;
				float s = c->weight[0][k], t = c->weight[1][k];
				int32_t member[4] = { c->member[vertex ? 1 : 0][k], c->member[vertex ? 2 : 1][k],
									  c->member[vertex ? 3 : 2][k], c->member[vertex ? 0 : 3][k] };
				float coef[4] = { -s, -t, -c->weight[2][k], 1.0f };
				if ( !vertex )
				{
					coef[0] = 1.0f - s, coef[1] = s, coef[2] = -( 1.0f - t ), coef[3] = -t;
				}
				for ( int r = 0; r < 4; ++r )
				{
					int32_t e = mine[member[r]]++;
					c->entries[e] = (int32_t) k;
					c->entry_coef[e] = coef[r];
				}
			}
		}
	}
}

/* Runs the exact test on block `block`'s listed pairs (see SKIN) that the motion since the listing
 * may have brought within the thickness (list_reach2), in their order, as the search would have
 * buffered them. */
static void replay_block( detect_context* c, const sere_collide* collide, int32_t block, bool vertices )
{
	size_t base = (size_t) collide->cache_block_thread[block] * (size_t) collide->cache_capacity +
				  (size_t) collide->cache_block_start[block];
	const int32_t *item = collide->cache_item + base, *target = collide->cache_target + base;
	const uint8_t* near = collide->cache_near + base;
	const float* gap = collide->cache_gap + base;
	int32_t count = collide->cache_block_count[block];
	float reach2 = collide->cache_reach2, sum = 0.0f;
	bool replay = replaying( c );
	void ( *flush )( detect_context* ) = vertices ? sere_coll_detect_flush : sere_coll_detect_edge_flush;
	c->pair_count = 0;
	for ( int32_t start = 0; start < count; start += CLOSEST_LANES )
	{
		int32_t lanes = count - start < CLOSEST_LANES ? count - start : CLOSEST_LANES;
		uint32_t keep = 0;
		for ( int32_t l = 0; l < lanes; ++l )
		{
			/* the floor loads the distances and takes the recorded outcome */
			if ( replay )
			{
				sum += gap[start + l];
			}
			else
			{
				/* a NaN bound is kept */
				keep |= ( uint32_t ) !( gap[start + l] > reach2 ) << l;
			}
		}
		keep = replay ? recorded_mask( c ) : traced_mask( c, keep );
		for ( ; keep != 0; keep &= keep - 1 )
		{
			if ( c->pair_count == PAIR_BUFFER )
			{
				flush( c );
			}
			int32_t k = start + __builtin_ctz( keep );
			c->pair_item[c->pair_count] = item[k];
			c->pair_target[c->pair_count] = target[k];
			c->pair_near[c->pair_count] = near[k];
			c->pair_count += 1;
		}
	}
	if ( replay )
	{
		c->run->sink += sum;
	}
	flush( c );
}

/* Vertex block b's range of vertices. */
static void block_range( const sere_collide* collide, int32_t b, int32_t* first, int32_t* end )
{
	*first = b * DETECT_BLOCK;
	*end = *first + DETECT_BLOCK < collide->vertex_count ? *first + DETECT_BLOCK : collide->vertex_count;
}

/* The shrink σ of positions x, y, z since the listing: the least-squares scale about the listing
 * positions' mean r̄, less one, Σ a · Δ / Σ |a|² with a = r − r̄ and Δ = x − r (0 for a list made
 * on one point). Any σ keeps list_serves' argument; this one takes most of a shrink off. Each
 * vertex block's sum is taken in vectors on one thread, and the blocks' are added in order in
 * double, so σ has the same bits on any number of threads. (Taking σ of the last served
 * detection instead, its sums riding on the residuals' pass, saves this pass, about 7% of a served
 * pass on the dense maple at 1 thread, but lists serve a fast shrink only one detection late.) */
static float list_shrink( sere_collide* collide, const float* x, const float* y, const float* z, int threads )
{
	const float *cx = collide->cache_x, *cy = collide->cache_y, *cz = collide->cache_z;
	const float m[3] = { collide->cache_mean[0], collide->cache_mean[1], collide->cache_mean[2] };
	double* partial = collide->cache_sum;
	int32_t blocks = collide->vertex_blocks;
#pragma omp parallel for num_threads( threads ) schedule( static )
	for ( int32_t b = 0; b < blocks; ++b )
	{
		int32_t first, end;
		block_range( collide, b, &first, &end );
		float sum = 0.0f;
#pragma omp simd reduction( + : sum )
		for ( int32_t i = first; i < end; ++i )
		{
			sum += ( ( cx[i] - m[0] ) * ( x[i] - cx[i] ) + ( cy[i] - m[1] ) * ( y[i] - cy[i] ) ) +
				   ( cz[i] - m[2] ) * ( z[i] - cz[i] );
		}
		partial[4 * (size_t) b] = sum;
	}
	double dot = sere_block_sum( partial, blocks, 0 );
	return collide->cache_spread > 0.0 ? (float) ( dot / collide->cache_spread ) : 0.0f;
}

/* True when the list (see SKIN) serves positions x, y, z and this thickness: it is whole, was made
 * for a thickness no smaller and for this build of the tree, and the motion since the listing is
 * a uniform scale s = 1 + σ about r̄ (list_shrink) and a translation T, which the list's argument
 * sees only through s, plus a residual e = Δ − σ a − T of every vertex no larger than
 * D = (s (h₀ + 2δ) − h₀) / 2, h₀ the listing's thickness. Then two points of a pair, convex
 * combinations of corners with the same weights then and now, are now at least s times their
 * distance then, less 2D, apart: a pair left off the list, farther than h₀ + 2δ then, is still
 * farther than h₀. With s = 1 that is every vertex within δ of where it was up to T; a drying
 * leaf shrinks all over, its rim soon farther than δ from where it was while no two nearby points
 * come much closer, which the scale takes off (the Table 1 maple dried to the end, 4660 points,
 * searches in 159 to 160 of its 1070 frames instead of 202 to 203). T is the middle of the box of
 * Δ − σ a. The float e is within a few ulps of |Δ| + |σ a| + |T| of the true one (Δ is a
 * difference of nearby values), and the (|T| + 2 |σ| far) 2⁻¹⁴ taken off D covers that and what T
 * and the scale add to cull_radius's |p| term, far inside the 2⁻⁸ δ of room the grown radius
 * keeps; a NaN fails the test (it never wins a bound; the last pass catches it). The bounds of the
 * box and of e run in vectors: a minimum or maximum does not depend on the order it is taken in.
 * When the list serves, D and s set which listed pairs the detection tests (list_reach2). */
static bool list_serves( sere_collide* collide, const sere_bvh* bvh, const float* x, const float* y, const float* z,
						 float thickness, int threads )
{
	if ( !collide->cache_valid || !( thickness <= collide->cache_thickness ) ||
		 sere_bvh_generation( bvh ) != collide->cache_generation )
	{
		return false;
	}
	int32_t n = collide->vertex_count;
	const float *cx = collide->cache_x, *cy = collide->cache_y, *cz = collide->cache_z;
	const float m[3] = { collide->cache_mean[0], collide->cache_mean[1], collide->cache_mean[2] };
	const float sigma = list_shrink( collide, x, y, z, threads );
	/* the three axes in one pass: one team started, not three */
	float lx = INFINITY, ly = INFINITY, lz = INFINITY, hx = -INFINITY, hy = -INFINITY, hz = -INFINITY;
#pragma omp parallel for simd num_threads( threads ) reduction( min : lx, ly, lz ) reduction( max : hx, hy, hz )
	for ( int32_t i = 0; i < n; ++i )
	{
		float dx = ( x[i] - cx[i] ) - sigma * ( cx[i] - m[0] ), dy = ( y[i] - cy[i] ) - sigma * ( cy[i] - m[1] );
		float dz = ( z[i] - cz[i] ) - sigma * ( cz[i] - m[2] );
		lx = dx < lx ? dx : lx, ly = dy < ly ? dy : ly, lz = dz < lz ? dz : lz;
		hx = dx > hx ? dx : hx, hy = dy > hy ? dy : hy, hz = dz > hz ? dz : hz;
	}
	float lo[3] = { lx, ly, lz }, hi[3] = { hx, hy, hz };
	if ( !( isfinite( lo[0] + lo[1] + lo[2] ) && isfinite( hi[0] + hi[1] + hi[2] ) ) )
	{
		return false;
	}
	float t[3] = { 0.5f * ( lo[0] + hi[0] ), 0.5f * ( lo[1] + hi[1] ), 0.5f * ( lo[2] + hi[2] ) };
	float shift = fabsf( t[0] ) + fabsf( t[1] ) + fabsf( t[2] ) + 2.0f * fabsf( sigma ) * collide->cache_far;
	float scale = 1.0f + sigma, h0 = collide->cache_thickness;
	float skin = 0.5f * ( scale * ( h0 + 2.0f * collide->cache_delta ) - h0 ) - shift * 0x1p-14f;
	if ( !( skin > 0.0f ) )
	{
		return false;
	}
	float limit = skin * skin, moved2 = 0.0f, far = 0.0f;
	int beyond = 0;
#pragma omp parallel for simd num_threads( threads ) reduction( | : beyond ) reduction( max : moved2, far )
	for ( int32_t i = 0; i < n; ++i )
	{
		float dx = ( x[i] - cx[i] ) - sigma * ( cx[i] - m[0] ) - t[0];
		float dy = ( y[i] - cy[i] ) - sigma * ( cy[i] - m[1] ) - t[1];
		float dz = ( z[i] - cz[i] ) - sigma * ( cz[i] - m[2] ) - t[2];
		float d2 = dx * dx + dy * dy + dz * dz, p = fabsf( x[i] ) + fabsf( y[i] ) + fabsf( z[i] );
		beyond |= !( d2 <= limit );
		moved2 = d2 > moved2 ? d2 : moved2;
		far = p > far ? p : far;
	}
	if ( beyond )
	{
		return false;
	}
	far = far > collide->cache_far ? far : collide->cache_far;
	collide->cache_reach2 = list_reach2( thickness, sqrtf( moved2 ), scale, far );
	return true;
}

/* The floor of list_serves (sere_collide_touch_served): its passes over the vertices, the same
 * loads with adds in place of the shrink's products and of the bounds of the residuals and of their
 * distances from the middle, in vectors as there (omp simd: a floor's sum may take any order). */
static float list_serves_touch( sere_collide* collide, const float* x, const float* y, const float* z, int threads )
{
	int32_t n = collide->vertex_count, blocks = collide->vertex_blocks;
	const float *cx = collide->cache_x, *cy = collide->cache_y, *cz = collide->cache_z;
	double* partial = collide->cache_sum;
#pragma omp parallel for num_threads( threads ) schedule( static )
	for ( int32_t b = 0; b < blocks; ++b )
	{
		int32_t first, end;
		block_range( collide, b, &first, &end );
		float sum = 0.0f;
#pragma omp simd reduction( + : sum )
		for ( int32_t i = first; i < end; ++i )
		{
			sum += ( ( x[i] + cx[i] ) + ( y[i] + cy[i] ) ) + ( z[i] + cz[i] );
		}
		partial[4 * (size_t) b] = sum;
	}
	float sum = 0.0f;
	for ( int32_t b = 0; b < blocks; ++b )
	{
		sum += (float) partial[4 * (size_t) b];
	}
	for ( int pass = 0; pass < 2; ++pass )
	{
#pragma omp parallel for simd num_threads( threads ) schedule( static ) reduction( + : sum )
		for ( int32_t i = 0; i < n; ++i )
		{
			sum += ( ( x[i] - cx[i] ) + ( y[i] - cy[i] ) ) + ( z[i] - cz[i] );
		}
	}
	return sum;
}

/* The threads a detection runs with: the team's, at most the workspace's slots. */
static int detect_threads( const sere_collide* collide )
{
	int threads = sere_team_for( collide->threads );
	return threads < collide->slots ? threads : collide->slots;
}

bool sere_coll_list_serves( sere_collide* collide, const sere_bvh* bvh, const float* x, const float* y, const float* z,
							float thickness )
{
	return list_serves( collide, bvh, x, y, z, thickness, detect_threads( collide ) );
}

/* Whether this detection replays the list (see SKIN; served as for sere_coll_detect) or searches
 * the tree, listing anew: then the skin adapts to how long the last list lasted and the edges'
 * across vectors are taken at these positions. */
static bool choose_list( sere_collide* collide, const sere_bvh* bvh, const int32_t* tri, const float* x, const float* y,
						 const float* z, float thickness, int threads, int served )
{
	bool replay = served < 0 ? list_serves( collide, bvh, x, y, z, thickness, threads ) : served > 0;
	if ( replay )
	{
		collide->cache_uses += 1;
	}
	else
	{
		if ( collide->cache_valid && collide->cache_uses < SKIN_SHORT )
		{
			collide->skin = collide->skin * 1.25f < SKIN_MAX ? collide->skin * 1.25f : SKIN_MAX;
		}
		else if ( collide->cache_valid && collide->cache_uses > SKIN_LONG )
		{
			collide->skin = collide->skin * 0.8f > SKIN_MIN ? collide->skin * 0.8f : SKIN_MIN;
		}
		collide->cache_valid = false;
		collide->cache_uses = 0;
		collide->cache_delta = collide->skin * thickness;
		int32_t edges = collide->edge_count;
#pragma omp parallel for num_threads( threads ) schedule( static )
		for ( int32_t e = 0; e < edges; ++e )
		{
			sere_coll_edge_across_at( collide, tri, x, y, z, e );
		}
	}
	return replay;
}

/* Thread tid's detection context. */
static void context_init( detect_context* c, const sere_collide* collide, const int32_t* tri, const float* x,
						  const float* y, const float* z, float thickness, bool listing, int tid )
{
	size_t across_stride = (size_t) sere_pad( collide->edge_count );
	*c = ( detect_context ){
		.x = x,
		.y = y,
		.z = z,
		.tri = tri,
		.edge_end = collide->edge_end,
		.lower_edge = collide->lower_edge,
		.owned = collide->owned,
		.edge_triangle = collide->edge_triangle,
		.rest_x = collide->rest_x,
		.rest_y = collide->rest_y,
		.rest_z = collide->rest_z,
		.mark_offset = collide->mark_offset,
		.mark_vertex = collide->mark_vertex,
		.mark_bits = collide->mark_bits,
		.mark = collide->lane_mark + (size_t) tid * (size_t) sere_pad( collide->vertex_count ),
		.h2 = thickness * thickness,
		.buffer = thread_buffer( collide, tid ),
		.edge_buffer = thread_edge_buffer( collide, tid ),
		.capacity = collide->capacity,
		.listing = listing,
		.thickness = thickness,
		/* 2δ, and 2⁻⁸ of it for the rounding of the displacement test and of cull_radius's
		 * |p| term at the moved positions */
		.grow = listing ? 2.0f * collide->cache_delta * ( 1.0f + 0x1p-8f ) : 0.0f,
		.list_item = collide->cache_item + (size_t) tid * (size_t) collide->cache_capacity,
		.list_target = collide->cache_target + (size_t) tid * (size_t) collide->cache_capacity,
		.list_near = collide->cache_near + (size_t) tid * (size_t) collide->cache_capacity,
		.list_gap = collide->cache_gap + (size_t) tid * (size_t) collide->cache_capacity,
		.list_capacity = collide->cache_capacity,
		.across = { collide->edge_across, collide->edge_across + across_stride,
					collide->edge_across + 2 * across_stride },
	};
}

/* The listing positions' mean, Σ |r − r̄|² and largest |x| + |y| + |z| (list_serves), each vertex
 * block's sums in double, added in block order: the same bits on any number of threads. */
static void keep_shape( sere_collide* collide, int threads )
{
	const float *cx = collide->cache_x, *cy = collide->cache_y, *cz = collide->cache_z;
	double* partial = collide->cache_sum;
	int32_t blocks = collide->vertex_blocks;
	float far = 0.0f;
#pragma omp parallel for num_threads( threads ) schedule( static ) reduction( max : far )
	for ( int32_t b = 0; b < blocks; ++b )
	{
		int32_t first, end;
		block_range( collide, b, &first, &end );
		double sum[3] = { 0.0, 0.0, 0.0 };
		for ( int32_t i = first; i < end; ++i )
		{
			sum[0] += cx[i], sum[1] += cy[i], sum[2] += cz[i];
			float p = fabsf( cx[i] ) + fabsf( cy[i] ) + fabsf( cz[i] );
			far = p > far ? p : far;
		}
		partial[4 * (size_t) b] = sum[0], partial[4 * (size_t) b + 1] = sum[1], partial[4 * (size_t) b + 2] = sum[2];
	}
	for ( int r = 0; r < 3; ++r )
	{
		collide->cache_mean[r] =
			collide->vertex_count > 0 ? (float) ( sere_block_sum( partial, blocks, r ) / collide->vertex_count ) : 0.0f;
	}
	const float m[3] = { collide->cache_mean[0], collide->cache_mean[1], collide->cache_mean[2] };
#pragma omp parallel for num_threads( threads ) schedule( static )
	for ( int32_t b = 0; b < blocks; ++b )
	{
		int32_t first, end;
		block_range( collide, b, &first, &end );
		double sum = 0.0;
		for ( int32_t i = first; i < end; ++i )
		{
			double a[3] = { cx[i] - m[0], cy[i] - m[1], cz[i] - m[2] };
			sum += ( a[0] * a[0] + a[1] * a[1] ) + a[2] * a[2];
		}
		partial[4 * (size_t) b] = sum;
	}
	collide->cache_spread = sere_block_sum( partial, blocks, 0 );
	collide->cache_far = far;
}

/* After a listing search: the list serves later detections when no thread outgrew its room and
 * every vertex was finite; it keeps the positions, thickness and tree build it was made for. */
static void keep_list( sere_collide* collide, const sere_bvh* bvh, const float* x, const float* y, const float* z,
					   float thickness, int threads, int bad )
{
	bool whole = !bad;
	for ( int t = 0; t < threads; ++t )
	{
		whole = whole && collide->cache_used[FAR_STRIDE * t] >= 0;
	}
	collide->cache_valid = whole;
	if ( !whole && !bad )
	{
		/* the list outgrew its room: the next one lists fewer pairs */
		collide->skin = SKIN_MIN;
	}
	if ( whole )
	{
		memcpy( collide->cache_x, x, sizeof( float ) * (size_t) collide->vertex_count );
		memcpy( collide->cache_y, y, sizeof( float ) * (size_t) collide->vertex_count );
		memcpy( collide->cache_z, z, sizeof( float ) * (size_t) collide->vertex_count );
		keep_shape( collide, threads );
		collide->cache_thickness = thickness;
		collide->cache_generation = sere_bvh_generation( bvh );
		/* until list_serves measures the motion, every listed pair is tested */
		collide->cache_reach2 = INFINITY;
	}
}

/* Runs block `block` with thread `run`'s context c: replays its listed pairs (replay), or searches
 * the tree, listing the pairs when listing; notes where its contacts and listed pairs went. Returns
 * nonzero when a vertex is not finite. */
static int run_block( sere_collide* collide, detect_context* c, const sere_bvh* bvh, int32_t block, float thickness,
					  bool replay, bool listing, int run )
{
	bool vertices = block < collide->vertex_blocks;
	int32_t start = vertices ? c->used : c->edge_used;
	int64_t found = vertices ? c->found : c->edge_found;
	int32_t listed = c->list_used;
	int bad = 0;
	if ( replay )
	{
		replay_block( c, collide, block, vertices );
	}
	else if ( vertices )
	{
		bad = sere_coll_detect_vertex_block( c, bvh, block, collide->vertex_count, thickness );
	}
	else
	{
		sere_coll_detect_edge_block( c, bvh, block - collide->vertex_blocks, collide->vertex_count, thickness );
	}
	if ( listing )
	{
		collide->cache_block_thread[block] = run;
		collide->cache_block_start[block] = listed;
		collide->cache_block_count[block] = c->list_used - listed;
	}
	collide->block_thread[block] = run;
	collide->block_start[block] = start;
	collide->block_found[block] = ( vertices ? c->found : c->edge_found ) - found;
	return bad;
}

/* After the blocks ran on `threads` threads: the contact counts (SERE_ERR_CAPACITY past the
 * capacity), each block's offset in the per-contact arrays and the lists (list_contacts). */
static sere_status list_found( sere_collide* collide, const int32_t* tri, int threads, int32_t* contact_count )
{
	int64_t total = 0, edge_total = 0;
	for ( int32_t block = 0; block < collide->block_count; ++block )
	{
		*( block < collide->vertex_blocks ? &total : &edge_total ) += collide->block_found[block];
	}
	*contact_count = total < INT32_MAX ? (int32_t) total : INT32_MAX;
	collide->edge_found = edge_total;
	if ( total > collide->capacity || edge_total > collide->capacity )
	{
		return SERE_ERR_CAPACITY;
	}
	/* block_found becomes each block's offset in the per-contact arrays: the vertex–triangle
	 * contacts, then the edge–edge ones */
	int64_t offset = 0;
	for ( int32_t block = 0; block < collide->block_count; ++block )
	{
		int64_t found = collide->block_found[block];
		collide->block_found[block] = offset;
		offset += found;
	}
	list_contacts( collide, tri, total, edge_total, threads );
	collide->contact_count = (int32_t) total;
	collide->edge_contact_count = (int32_t) edge_total;
	return SERE_OK;
}

/* sere_coll_detect, recording it into record when that is not NULL: the search's walks and tests,
 * or a served detection's exact tests. */
static sere_status detect( sere_collide* collide, const sere_bvh* bvh, const float* x, const float* y, const float* z,
						   float thickness, int served, collide_record* record, int32_t* contact_count )
{
	if ( collide == NULL || bvh == NULL || x == NULL || y == NULL || z == NULL || contact_count == NULL ||
		 !( thickness > 0.0f ) || !isfinite( thickness ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	int32_t triangles;
	const int32_t* tri = sere_bvh_triangles( bvh, &triangles );
	if ( sere_bvh_vertex_count( bvh ) != collide->vertex_count || triangles != collide->triangle_count )
	{
		return SERE_ERR_ARGUMENT;
	}
	collide->state += 1;
	*contact_count = 0;
	collide->contact_count = 0;
	collide->edge_contact_count = 0;
	collide->edge_found = 0;
	collide->touched_count = 0;
	int32_t threads = detect_threads( collide );
	bool replay = choose_list( collide, bvh, tri, x, y, z, thickness, threads, served );
	bool listing = !replay;
	/* A served detection's work is its listed pairs' exact tests, known before it runs (one more
	 * per block for the block's own steps); a search's is timed, and the last search's times cut
	 * this one. Reading the clock around each block took a sixth to a fifth of a served pass. */
	collide->work_prefix[0] = 0;
	for ( int32_t block = 0; block < collide->block_count; ++block )
	{
		int64_t work = replay ? (int64_t) collide->cache_block_count[block] + 1 : collide->block_work[block];
		collide->work_prefix[block + 1] = collide->work_prefix[block] + work;
	}
	for ( int t = 0; t < threads; ++t )
	{
		/* a thread the team turns out not to have lists nothing */
		collide->cache_used[FAR_STRIDE * t] = 0;
	}
	int bad = 0;
#pragma omp parallel num_threads( threads ) reduction( | : bad )
	{
		int tid = omp_get_thread_num(), team = omp_get_num_threads();
		detect_context c;
		context_init( &c, collide, tri, x, y, z, thickness, listing, tid );
		int32_t run_first = run_begin( collide, tid, team ), run_end = run_begin( collide, tid + 1, team );
		if ( record != NULL )
		{
			c.run = record->run + tid;
			record->run_first[tid] = run_first;
			if ( tid == 0 )
			{
				record->runs = team;
				record->run_first[team] = collide->block_count;
			}
		}
		for ( int32_t block = run_first; block < run_end; ++block )
		{
			double clock = replay ? 0.0 : omp_get_wtime();
			bad |= run_block( collide, &c, bvh, block, thickness, replay, listing, tid );
			if ( !replay )
			{
				collide->block_work[block] = (int64_t) ( ( omp_get_wtime() - clock ) * 1e9 );
			}
		}
		collide->cache_used[FAR_STRIDE * tid] = c.list_used;
	}
	if ( listing )
	{
		keep_list( collide, bvh, x, y, z, thickness, threads, bad );
	}
	if ( bad )
	{
		return SERE_ERR_NONFINITE;
	}
	return list_found( collide, tri, threads, contact_count );
}

sere_status sere_collide_detect( sere_collide* collide, const sere_bvh* bvh, const float* x, const float* y,
								 const float* z, float thickness, int32_t* contact_count )
{
	return detect( collide, bvh, x, y, z, thickness, -1, NULL, contact_count );
}

sere_status sere_coll_detect( sere_collide* collide, const sere_bvh* bvh, const float* x, const float* y,
							  const float* z, float thickness, int served, int32_t* contact_count )
{
	return detect( collide, bvh, x, y, z, thickness, served, NULL, contact_count );
}

/* What the record's runs counted, and the contacts listed. */
static sere_collide_traffic record_traffic( const sere_collide* collide, const collide_record* record )
{
	sere_collide_traffic traffic = { 0 };
	for ( int32_t r = 0; r < record->runs; ++r )
	{
		const collide_run* run = record->run + r;
		traffic.nodes += run->trace.nodes;
		traffic.leaves += run->trace.leaves;
		traffic.bound_pairs += run->bound_pairs;
		traffic.exact_pairs += run->exact_pairs;
	}
	traffic.contacts = (int64_t) collide->contact_count + collide->edge_contact_count;
	return traffic;
}

/* Readies each run's record for recording (replay false) or for a replay. */
static void reset_runs( collide_record* record, int32_t runs, bool replay )
{
	for ( int32_t r = 0; r < runs; ++r )
	{
		collide_run* run = record->run + r;
		run->trace.size = replay ? run->trace.size : 0;
		run->trace.at = 0;
		run->trace.nodes = run->trace.leaves = 0;
		run->trace.replay = replay;
		run->trace.failed = false;
		run->bound_pairs = run->exact_pairs = 0;
	}
}

sere_status sere_coll_record_detect( sere_collide* collide, const sere_bvh* bvh, const float* x, const float* y,
									 const float* z, float thickness, int served, sere_collide_traffic* traffic )
{
	if ( collide == NULL )
	{
		return SERE_ERR_ARGUMENT;
	}
	if ( collide->record == NULL && ( collide->record = sere_alloc( sizeof( collide_record ) ) ) == NULL )
	{
		return SERE_ERR_MEMORY;
	}
	collide_record* record = collide->record;
	record->valid = false;
	reset_runs( record, SERE_MAX_THREADS, false );
	int32_t contacts;
	sere_status status = detect( collide, bvh, x, y, z, thickness, served, record, &contacts );
	for ( int32_t r = 0; status == SERE_OK && r < record->runs; ++r )
	{
		status = record->run[r].trace.failed ? SERE_ERR_MEMORY : SERE_OK;
	}
	if ( status != SERE_OK )
	{
		return status;
	}
	record->valid = true;
	record->served = served > 0;
	record->generation = sere_bvh_generation( bvh );
	record->state = collide->state;
	record->thickness = thickness;
	record->listed = !record->served && collide->cache_valid;
	record->one = 1.0f;
	record->evaluations = 0;
	if ( traffic != NULL )
	{
		*traffic = record_traffic( collide, record );
	}
	return SERE_OK;
}

sere_status sere_collide_record_search( sere_collide* collide, const sere_bvh* bvh, const float* x, const float* y,
										const float* z, float thickness, sere_collide_traffic* traffic )
{
	return sere_coll_record_detect( collide, bvh, x, y, z, thickness, 0, traffic );
}

sere_status sere_coll_touch_detect( sere_collide* collide, const sere_bvh* bvh, const float* x, const float* y,
									const float* z, bool served, sere_collide_traffic* traffic )
{
	if ( collide == NULL || bvh == NULL || x == NULL || y == NULL || z == NULL )
	{
		return SERE_ERR_ARGUMENT;
	}
	collide_record* record = collide->record;
	int32_t triangles;
	const int32_t* tri = sere_bvh_triangles( bvh, &triangles );
	if ( record == NULL || !record->valid || record->served != served || record->state != collide->state ||
		 record->generation != sere_bvh_generation( bvh ) || sere_bvh_vertex_count( bvh ) != collide->vertex_count ||
		 triangles != collide->triangle_count )
	{
		return SERE_ERR_ARGUMENT;
	}
	int32_t runs = record->runs, n = collide->vertex_count, edges = collide->edge_count;
	/* the threads a detection would run with now, as many as the recorded runs at most */
	int threads = detect_threads( collide ) < runs ? detect_threads( collide ) : runs;
	float one = record->one, sum = 0.0f;
	reset_runs( record, runs, true );
	if ( served )
	{
		/* sere_collide_resolve's check that the list serves */
		sum += list_serves_touch( collide, x, y, z, detect_threads( collide ) );
	}
	else
	{
		/* choose_list's across vectors */
#pragma omp parallel for num_threads( threads ) schedule( static ) reduction( + : sum )
		for ( int32_t e = 0; e < edges; ++e )
		{
			sum += sere_coll_edge_across_touch( collide, tri, x, y, z, e, one );
		}
	}
#pragma omp parallel num_threads( threads )
	{
		/* each run as the recorded thread of that number ran it, whichever thread runs it: the
		 * search's blocks listing their pairs, or the served detection's replaying the list */
		for ( int32_t r = omp_get_thread_num(); r < runs; r += omp_get_num_threads() )
		{
			detect_context c;
			context_init( &c, collide, tri, x, y, z, record->thickness, !served, r );
			c.run = record->run + r;
			c.one = one;
			for ( int32_t block = record->run_first[r]; block < record->run_first[r + 1]; ++block )
			{
				run_block( collide, &c, bvh, block, record->thickness, served, !served, r );
			}
			collide->cache_used[FAR_STRIDE * r] = c.list_used;
		}
	}
	/* keep_list's copy of the positions, and keep_shape's two passes over the copy */
	if ( record->listed )
	{
		for ( int32_t i = 0; i < n; ++i )
		{
			sum += ( x[i] + y[i] ) + z[i];
			collide->cache_x[i] *= one, collide->cache_y[i] *= one, collide->cache_z[i] *= one;
		}
		for ( int pass = 0; pass < 2; ++pass )
		{
			for ( int32_t i = 0; i < n; ++i )
			{
				sum += ( collide->cache_x[i] + collide->cache_y[i] ) + collide->cache_z[i];
			}
		}
	}
	record->sink += sum;
	int32_t contacts;
	sere_status status = list_found( collide, tri, threads, &contacts );
	if ( traffic != NULL )
	{
		*traffic = record_traffic( collide, record );
	}
	return status;
}

sere_status sere_collide_touch_search( sere_collide* collide, const sere_bvh* bvh, const float* x, const float* y,
									   const float* z, sere_collide_traffic* traffic )
{
	return sere_coll_touch_detect( collide, bvh, x, y, z, false, traffic );
}
