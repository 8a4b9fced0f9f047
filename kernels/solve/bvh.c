/* _GNU_SOURCE: sched_getaffinity for internal/team.h. */
#define _GNU_SOURCE

#include "core/array.h"
#include "solve/internal/bvh_shared.h"

#include <math.h>
#include <stdatomic.h>
#include <string.h>

static float box_area( float lx, float ly, float lz, float hx, float hy, float hz )
{
	float dx = hx - lx, dy = hy - ly, dz = hz - lz;
	return 2.0f * ( dx * dy + dy * dz + dz * dx );
}

static box3 box_empty( void )
{
	box3 b = { { INFINITY, INFINITY, INFINITY }, { -INFINITY, -INFINITY, -INFINITY } };
	return b;
}

static void box_grow( box3* b, const sere_bvh* bvh, int32_t t )
{
	b->lo[0] = sere_min_x86( b->lo[0], bvh->lo_x[t] );
	b->lo[1] = sere_min_x86( b->lo[1], bvh->lo_y[t] );
	b->lo[2] = sere_min_x86( b->lo[2], bvh->lo_z[t] );
	b->hi[0] = sere_max_x86( b->hi[0], bvh->hi_x[t] );
	b->hi[1] = sere_max_x86( b->hi[1], bvh->hi_y[t] );
	b->hi[2] = sere_max_x86( b->hi[2], bvh->hi_z[t] );
}

static void box_merge( box3* b, const box3* other )
{
	for ( int a = 0; a < 3; ++a )
	{
		b->lo[a] = sere_min_x86( b->lo[a], other->lo[a] );
		b->hi[a] = sere_max_x86( b->hi[a], other->hi[a] );
	}
}

static float box3_area( const box3* b )
{
	return box_area( b->lo[0], b->lo[1], b->lo[2], b->hi[0], b->hi[1], b->hi[2] );
}

static float range_area( const sere_bvh* bvh, int32_t begin, int32_t end )
{
	box3 b = box_empty();
	for ( int32_t i = begin; i < end; ++i )
	{
		box_grow( &b, bvh, bvh->order[i] );
	}
	return box3_area( &b );
}

/* Reorders order[begin, end) so that position nth holds the element a full sort by key would
 * put there, smaller-or-equal keys before it (Hoare partition with a middle pivot: fixed, so
 * the build is deterministic, and equal keys do not degrade it). */
static void select_nth( int32_t* order, const float* key, int32_t begin, int32_t end, int32_t nth )
{
	int32_t lo = begin, hi = end - 1;
	while ( lo < hi )
	{
		float pivot = key[order[lo + ( hi - lo ) / 2]];
		int32_t i = lo, j = hi;
		while ( i <= j )
		{
			while ( key[order[i]] < pivot )
			{
				++i;
			}
			while ( key[order[j]] > pivot )
			{
				--j;
			}
			if ( i <= j )
			{
				int32_t swap = order[i];
				order[i] = order[j];
				order[j] = swap;
				++i;
				--j;
			}
		}
		if ( nth <= j )
		{
			hi = j;
		}
		else if ( nth >= i )
		{
			lo = i;
		}
		else
		{
			break;
		}
	}
}

static int32_t bin_of( float c, float lo, float scale )
{
	int32_t b = (int32_t) ( ( c - lo ) * scale );
	return b < 0 ? 0 : ( b >= BIN_COUNT ? BIN_COUNT - 1 : b );
}

/* Splits order[begin, end) (at least two triangles) in two non-empty parts and returns the
 * first index of the second: the cheapest binned SAH plane over the three axes, or the object
 * median along the widest axis below SAH_DEPTH_LIMIT or when binning cannot separate. */
static int32_t split_range( sere_bvh* bvh, int32_t begin, int32_t end, int32_t depth )
{
	int32_t* order = bvh->order;
	const float* centre[3] = { bvh->c_x, bvh->c_y, bvh->c_z };
	float clo[3] = { INFINITY, INFINITY, INFINITY }, chi[3] = { -INFINITY, -INFINITY, -INFINITY };
	for ( int32_t i = begin; i < end; ++i )
	{
		for ( int a = 0; a < 3; ++a )
		{
			clo[a] = sere_min_x86( clo[a], centre[a][order[i]] );
			chi[a] = sere_max_x86( chi[a], centre[a][order[i]] );
		}
	}
	int widest = 0;
	for ( int a = 1; a < 3; ++a )
	{
		widest = chi[a] - clo[a] > chi[widest] - clo[widest] ? a : widest;
	}
	if ( !( chi[widest] > clo[widest] ) )
	{
		/* every centre coincides: any split is as good as another */
		return begin + ( end - begin ) / 2;
	}

	if ( depth < SAH_DEPTH_LIMIT && end - begin > 2 )
	{
		float best_cost = INFINITY;
		int best_axis = -1, best_bin = 0;
		float best_scale = 0.0f;
		for ( int a = 0; a < 3; ++a )
		{
			if ( !( chi[a] > clo[a] ) )
			{
				continue;
			}
			float scale = (float) BIN_COUNT / ( chi[a] - clo[a] );
			int32_t count[BIN_COUNT] = { 0 };
			box3 bins[BIN_COUNT];
			for ( int k = 0; k < BIN_COUNT; ++k )
			{
				bins[k] = box_empty();
			}
			for ( int32_t i = begin; i < end; ++i )
			{
				int32_t b = bin_of( centre[a][order[i]], clo[a], scale );
				count[b] += 1;
				box_grow( &bins[b], bvh, order[i] );
			}
			/* right_cost[k]: area × count of bins k + 1 .. BIN_COUNT − 1 */
			float right_cost[BIN_COUNT];
			box3 right = box_empty();
			int32_t right_count = 0;
			for ( int k = BIN_COUNT - 1; k > 0; --k )
			{
				box_merge( &right, &bins[k] );
				right_count += count[k];
				right_cost[k - 1] = right_count > 0 ? box3_area( &right ) * (float) right_count : 0.0f;
			}
			box3 left = box_empty();
			int32_t left_count = 0;
			for ( int k = 0; k < BIN_COUNT - 1; ++k )
			{
				box_merge( &left, &bins[k] );
				left_count += count[k];
				if ( left_count == 0 || left_count == end - begin )
				{
					continue;
				}
				float cost = box3_area( &left ) * (float) left_count + right_cost[k];
				if ( cost < best_cost )
				{
					best_cost = cost;
					best_axis = a;
					best_bin = k;
					best_scale = scale;
				}
			}
		}
		if ( best_axis >= 0 )
		{
			const float* key = centre[best_axis];
			int32_t i = begin, j = end - 1;
			while ( i <= j )
			{
				if ( bin_of( key[order[i]], clo[best_axis], best_scale ) <= best_bin )
				{
					++i;
				}
				else
				{
					int32_t swap = order[i];
					order[i] = order[j];
					order[j] = swap;
					--j;
				}
			}
			if ( i > begin && i < end )
			{
				return i;
			}
		}
	}

	int32_t mid = begin + ( end - begin ) / 2;
	select_nth( order, centre[widest], begin, end, mid );
	return mid;
}

typedef struct child_range
{
	int32_t begin, end, depth;
	float area;
} child_range;

/* Opens the node's triangle range into up to eight child ranges (collapsing a binary SAH tree
 * into a wide one), then allocates the internal children contiguously and queues them. A range
 * of at most eight triangles becomes a bottom node holding each in a lane; larger ranges are
 * split, the one with the largest box first, until eight lanes are used or every range fits a
 * bottom node. Splitting ranges that already fit would leave the bottom nodes, most of the tree,
 * half empty. */
static void build_node( sere_bvh* bvh, build_item item, int32_t* stack_size )
{
	child_range ranges[SERE_BVH_WIDTH];
	int32_t count = 1;
	ranges[0] = ( child_range ){ item.begin, item.end, item.depth, range_area( bvh, item.begin, item.end ) };
	int32_t smallest_split = item.end - item.begin > SERE_BVH_WIDTH ? SERE_BVH_WIDTH + 1 : 2;
	while ( count < SERE_BVH_WIDTH )
	{
		int32_t best = -1;
		for ( int32_t k = 0; k < count; ++k )
		{
			if ( ranges[k].end - ranges[k].begin >= smallest_split &&
				 ( best < 0 || ranges[k].area > ranges[best].area ) )
			{
				best = k;
			}
		}
		if ( best < 0 )
		{
			break;
		}
		child_range r = ranges[best];
		int32_t mid = split_range( bvh, r.begin, r.end, r.depth );
		memmove( ranges + best + 2, ranges + best + 1, sizeof( child_range ) * (size_t) ( count - best - 1 ) );
		ranges[best] = ( child_range ){ r.begin, mid, r.depth + 1, range_area( bvh, r.begin, mid ) };
		ranges[best + 1] = ( child_range ){ mid, r.end, r.depth + 1, range_area( bvh, mid, r.end ) };
		count += 1;
	}

	sere_bvh_node* node = bvh->nodes + item.node;
	int32_t level = bvh->node_level[item.node];
	build_item pending[SERE_BVH_WIDTH];
	int32_t pending_count = 0;
	for ( int32_t k = 0; k < SERE_BVH_WIDTH; ++k )
	{
		/* the boxes are filled by the refit that ends the build */
		node->min_x[k] = node->min_y[k] = node->min_z[k] = INFINITY;
		node->max_x[k] = node->max_y[k] = node->max_z[k] = -INFINITY;
		if ( k >= count )
		{
			node->child[k] = SERE_BVH_EMPTY;
		}
		else if ( ranges[k].end - ranges[k].begin == 1 )
		{
			node->child[k] = ~bvh->order[ranges[k].begin];
		}
		else
		{
			int32_t child = bvh->node_count++;
			bvh->node_level[child] = level + 1;
			node->child[k] = child;
			pending[pending_count++] = ( build_item ){ child, ranges[k].begin, ranges[k].end, ranges[k].depth };
		}
	}
	/* reverse order, so the first child is built next: subtrees then lie in depth-first order */
	for ( int32_t k = pending_count - 1; k >= 0; --k )
	{
		bvh->stack[( *stack_size )++] = pending[k];
	}
}

/* Recomputes the node's lane boxes from its children (already refit: they are refit first) or
 * from its triangles' vertices, and the area of its own box, kept in registers as the lanes
 * are written (reading the lanes back would stall on the stores just made). */
static void refit_node( sere_bvh* bvh, int32_t n, const float* x, const float* y, const float* z )
{
	sere_bvh_node* node = bvh->nodes + n;
	float nlx = INFINITY, nly = INFINITY, nlz = INFINITY, nhx = -INFINITY, nhy = -INFINITY, nhz = -INFINITY;
	for ( int k = 0; k < SERE_BVH_WIDTH; ++k )
	{
		int32_t c = node->child[k];
		float lx, ly, lz, hx, hy, hz;
		if ( c >= 0 )
		{
			const sere_bvh_node* child = bvh->nodes + c;
			lx = sere_v8_min_all( child->min_x ), ly = sere_v8_min_all( child->min_y ),
			lz = sere_v8_min_all( child->min_z );
			hx = sere_v8_max_all( child->max_x ), hy = sere_v8_max_all( child->max_y ),
			hz = sere_v8_max_all( child->max_z );
		}
		else if ( c != SERE_BVH_EMPTY )
		{
			const int32_t* v = bvh->tri + 3 * (size_t) ~c;
			float ax = x[v[0]], ay = y[v[0]], az = z[v[0]];
			float bx = x[v[1]], by = y[v[1]], bz = z[v[1]];
			float cx = x[v[2]], cy = y[v[2]], cz = z[v[2]];
			lx = sere_min_x86( ax, sere_min_x86( bx, cx ) ), ly = sere_min_x86( ay, sere_min_x86( by, cy ) ),
			lz = sere_min_x86( az, sere_min_x86( bz, cz ) );
			hx = sere_max_x86( ax, sere_max_x86( bx, cx ) ), hy = sere_max_x86( ay, sere_max_x86( by, cy ) ),
			hz = sere_max_x86( az, sere_max_x86( bz, cz ) );
		}
		else
		{
			continue;
		}
		node->min_x[k] = lx, node->min_y[k] = ly, node->min_z[k] = lz;
		node->max_x[k] = hx, node->max_y[k] = hy, node->max_z[k] = hz;
		nlx = sere_min_x86( nlx, lx ), nly = sere_min_x86( nly, ly ), nlz = sere_min_x86( nlz, lz );
		nhx = sere_max_x86( nhx, hx ), nhy = sere_max_x86( nhy, hy ), nhz = sere_max_x86( nhz, hz );
	}
	bvh->node_area[n] = box_area( nlx, nly, nlz, nhx, nhy, nhz );
}

/* Refits every box in one parallel region: subtrees rooted two levels down (up to 64 of them)
 * are shared out statically, each refit bottom-up in reverse index order (children always
 * follow their parent), then one thread finishes the few nodes above. One fork and two
 * barriers, where a level-by-level refit pays a barrier per level; and a static share gives
 * each thread the same subtrees every frame, so their nodes stay in its cache instead of
 * moving between cores. Returns false, boxes untouched, when a position is NaN or infinite.
 *
 * Then the quality: the surface area heuristic's cost of the internal nodes,
 * Σ area(node) / area(root) over the nodes below the root (the expected number of node boxes a
 * query crossing the root box enters), summed in node order: a fixed order, so the ratio and
 * the rebuild decision are the same for every thread count. */
static bool refit_tree( sere_bvh* bvh, const float* x, const float* y, const float* z )
{
	int32_t cut = bvh->cut_level;
	int32_t n = bvh->vertex_count;
	int bad = 0;
#pragma omp parallel num_threads( sere_team_for( bvh->threads ) )
	{
#pragma omp for reduction( | : bad ) schedule( static )
		for ( int32_t v = 0; v < n; ++v )
		{
			bad |= !( isfinite( x[v] ) && isfinite( y[v] ) && isfinite( z[v] ) );
		}
		if ( !bad )
		{
#pragma omp for schedule( static )
			for ( int32_t i = 0; i < bvh->cut_count; ++i )
			{
				int32_t root = bvh->cut_roots[i];
				for ( int32_t node = bvh->subtree_end[root] - 1; node >= bvh->subtree_begin[root]; --node )
				{
					refit_node( bvh, node, x, y, z );
				}
				refit_node( bvh, root, x, y, z );
			}
		}
	}
	if ( bad )
	{
		return false;
	}
	for ( int32_t level = cut - 1; level >= 0; --level )
	{
		for ( int32_t i = bvh->level_start[level]; i < bvh->level_start[level + 1]; ++i )
		{
			refit_node( bvh, bvh->level_nodes[i], x, y, z );
		}
	}
	double nodes = 0.0;
	for ( int32_t i = 1; i < bvh->node_count; ++i )
	{
		nodes += bvh->node_area[i];
	}
	bvh->quality = bvh->node_area[0] > 0.0f ? nodes / bvh->node_area[0] : 1.0;
	return true;
}

/* Each triangle's box, its centre and the identity order, for the build. */
static void triangle_boxes( sere_bvh* bvh, const float* x, const float* y, const float* z )
{
	int32_t n = bvh->triangle_count;
#pragma omp parallel for num_threads( sere_team_for( bvh->threads ) ) schedule( static )
	for ( int32_t t = 0; t < n; ++t )
	{
		const int32_t* v = bvh->tri + 3 * (size_t) t;
		bvh->lo_x[t] = sere_min_x86( x[v[0]], sere_min_x86( x[v[1]], x[v[2]] ) );
		bvh->lo_y[t] = sere_min_x86( y[v[0]], sere_min_x86( y[v[1]], y[v[2]] ) );
		bvh->lo_z[t] = sere_min_x86( z[v[0]], sere_min_x86( z[v[1]], z[v[2]] ) );
		bvh->hi_x[t] = sere_max_x86( x[v[0]], sere_max_x86( x[v[1]], x[v[2]] ) );
		bvh->hi_y[t] = sere_max_x86( y[v[0]], sere_max_x86( y[v[1]], y[v[2]] ) );
		bvh->hi_z[t] = sere_max_x86( z[v[0]], sere_max_x86( z[v[1]], z[v[2]] ) );
		bvh->c_x[t] = 0.5f * ( bvh->lo_x[t] + bvh->hi_x[t] );
		bvh->c_y[t] = 0.5f * ( bvh->lo_y[t] + bvh->hi_y[t] );
		bvh->c_z[t] = 0.5f * ( bvh->lo_z[t] + bvh->hi_z[t] );
		bvh->order[t] = t;
	}
}

/* The nodes grouped by level (for the parallel bottom-up refit) and each node's subtree range. */
static void group_levels( sere_bvh* bvh )
{
	/* group nodes by level for the parallel bottom-up refit */
	int32_t levels = 0;
	for ( int32_t i = 0; i < bvh->node_count; ++i )
	{
		levels = bvh->node_level[i] + 1 > levels ? bvh->node_level[i] + 1 : levels;
	}
	bvh->level_count = levels;
	memset( bvh->level_start, 0, sizeof( int32_t ) * (size_t) ( levels + 1 ) );
	for ( int32_t i = 0; i < bvh->node_count; ++i )
	{
		bvh->level_start[bvh->node_level[i] + 1] += 1;
	}
	for ( int32_t l = 0; l < levels; ++l )
	{
		bvh->level_start[l + 1] += bvh->level_start[l];
	}
	for ( int32_t i = 0; i < bvh->node_count; ++i )
	{
		/* level_start[l] runs ahead while filling and is shifted back below */
		bvh->level_nodes[bvh->level_start[bvh->node_level[i]]++] = i;
	}
	for ( int32_t l = levels; l > 0; --l )
	{
		bvh->level_start[l] = bvh->level_start[l - 1];
	}
	bvh->level_start[0] = 0;
	for ( int32_t i = bvh->node_count - 1; i >= 0; --i )
	{
		int32_t begin = INT32_MAX, end = i + 1;
		for ( int k = 0; k < SERE_BVH_WIDTH; ++k )
		{
			int32_t c = bvh->nodes[i].child[k];
			if ( c >= 0 )
			{
				begin = c < begin ? c : begin;
				end = bvh->subtree_end[c] > end ? bvh->subtree_end[c] : end;
			}
		}
		bvh->subtree_begin[i] = begin < end ? begin : end;
		bvh->subtree_end[i] = end;
	}
}

/* For every lane of every node, the highest vertex of the triangles below it. */
static void child_tops( sere_bvh* bvh )
{
	/* children come after their parent: bottom-up from the last node */
	for ( int32_t i = bvh->node_count - 1; i >= 0; --i )
	{
		for ( int k = 0; k < SERE_BVH_WIDTH; ++k )
		{
			int32_t c = bvh->nodes[i].child[k], top = -1;
			if ( c >= 0 )
			{
				for ( int j = 0; j < SERE_BVH_WIDTH; ++j )
				{
					int32_t below = bvh->child_top[(size_t) c * SERE_BVH_WIDTH + (size_t) j];
					top = below > top ? below : top;
				}
			}
			else if ( c != SERE_BVH_EMPTY )
			{
				for ( int r = 0; r < 3; ++r )
				{
					int32_t v = bvh->tri[3 * (size_t) ~c + (size_t) r];
					top = v > top ? v : top;
				}
			}
			bvh->child_top[(size_t) i * SERE_BVH_WIDTH + (size_t) k] = top;
		}
	}
}

/* The subtree roots at the cut level (at most 2), ordered by the mean first vertex of their
 * triangles, for the parallel refit's order by vertex index. */
static void order_cut( sere_bvh* bvh )
{
	const int32_t levels = bvh->level_count;
	bvh->cut_level = levels - 1 < 2 ? levels - 1 : 2;
	bvh->cut_count = bvh->level_start[bvh->cut_level + 1] - bvh->level_start[bvh->cut_level];
	for ( int32_t i = 0; i < bvh->cut_count; ++i )
	{
		int32_t root = bvh->level_nodes[bvh->level_start[bvh->cut_level] + i];
		double sum = 0.0, count = 0.0;
		for ( int32_t node = root; node < bvh->subtree_end[root];
			  node = node == root ? bvh->subtree_begin[root] : node + 1 )
		{
			for ( int k = 0; k < SERE_BVH_WIDTH; ++k )
			{
				int32_t c = bvh->nodes[node].child[k];
				if ( c < 0 && c != SERE_BVH_EMPTY )
				{
					sum += bvh->tri[3 * (size_t) ~c];
					count += 1.0;
				}
			}
		}
		double key = sum / count;
		/* insertion sort by key (ties keep level order): at most 64 roots */
		int32_t j = i;
		while ( j > 0 && bvh->cut_key[j - 1] > key )
		{
			bvh->cut_key[j] = bvh->cut_key[j - 1];
			bvh->cut_roots[j] = bvh->cut_roots[j - 1];
			--j;
		}
		bvh->cut_key[j] = key;
		bvh->cut_roots[j] = root;
	}
}

/* Builds so far, of every BVH in the process: each build's generation is its ordinal. */
static _Atomic uint64_t builds;

sere_status sere_bvh_build( sere_bvh* bvh, const float* x, const float* y, const float* z )
{
	if ( bvh == NULL || x == NULL || y == NULL || z == NULL )
	{
		return SERE_ERR_ARGUMENT;
	}
	if ( !sere_array_finite( ( const float* const[] ){ x, y, z }, 3, bvh->vertex_count, bvh->threads ) )
	{
		return SERE_ERR_NONFINITE;
	}
	triangle_boxes( bvh, x, y, z );

	bvh->node_count = 1;
	bvh->node_level[0] = 0;
	int32_t stack_size = 0;
	bvh->stack[stack_size++] = ( build_item ){ 0, 0, bvh->triangle_count, 0 };
	while ( stack_size > 0 )
	{
		build_item item = bvh->stack[--stack_size];
		build_node( bvh, item, &stack_size );
	}

	group_levels( bvh );
	child_tops( bvh );
	order_cut( bvh );
	refit_tree( bvh, x, y, z );
	bvh->quality_built = bvh->quality;
	bvh->generation = atomic_fetch_add( &builds, 1 ) + 1;
	return SERE_OK;
}

sere_status sere_bvh_create( const int32_t* tri, int32_t triangle_count, int32_t vertex_count, const float* x,
							 const float* y, const float* z, sere_bvh** out )
{
	if ( out == NULL )
	{
		return SERE_ERR_ARGUMENT;
	}
	*out = NULL;
	if ( tri == NULL || x == NULL || y == NULL || z == NULL || triangle_count < 1 || vertex_count < 1 ||
		 triangle_count > INT32_MAX / 3 )
	{
		return SERE_ERR_ARGUMENT;
	}
	for ( int64_t i = 0; i < 3 * (int64_t) triangle_count; ++i )
	{
		if ( tri[i] < 0 || tri[i] >= vertex_count )
		{
			return SERE_ERR_ARGUMENT;
		}
	}
	sere_bvh* bvh = sere_alloc( sizeof( sere_bvh ) );
	if ( bvh == NULL )
	{
		return SERE_ERR_MEMORY;
	}
	int32_t n = triangle_count;
	/* every internal node has at least two children, so n − 1 nodes suffice (one for n = 1) */
	int32_t capacity = n > 1 ? n - 1 : 1;
	size_t fn = sizeof( float ) * (size_t) sere_pad( n );
	bvh->triangle_count = n;
	bvh->vertex_count = vertex_count;
	bvh->node_capacity = capacity;
	bvh->tri = sere_alloc( sizeof( int32_t ) * 3 * (size_t) n );
	bvh->nodes = sere_alloc( sizeof( sere_bvh_node ) * (size_t) capacity );
	bvh->node_level = sere_alloc( sizeof( int32_t ) * (size_t) capacity );
	bvh->level_nodes = sere_alloc( sizeof( int32_t ) * (size_t) capacity );
	bvh->level_start = sere_alloc( sizeof( int32_t ) * ( (size_t) capacity + 1 ) );
	bvh->subtree_begin = sere_alloc( sizeof( int32_t ) * (size_t) capacity );
	bvh->subtree_end = sere_alloc( sizeof( int32_t ) * (size_t) capacity );
	bvh->cut_roots = sere_alloc( sizeof( int32_t ) * (size_t) capacity );
	bvh->cut_key = sere_alloc( sizeof( double ) * (size_t) capacity );
	bvh->node_area = sere_alloc( sizeof( float ) * (size_t) capacity );
	bvh->child_top = sere_alloc( sizeof( int32_t ) * SERE_BVH_WIDTH * (size_t) capacity );
	float** scratch[] = { &bvh->lo_x, &bvh->lo_y, &bvh->lo_z, &bvh->hi_x, &bvh->hi_y,
						  &bvh->hi_z, &bvh->c_x,  &bvh->c_y,  &bvh->c_z };
	bool ok = bvh->tri && bvh->nodes && bvh->node_level && bvh->level_nodes && bvh->level_start && bvh->subtree_begin &&
			  bvh->subtree_end && bvh->cut_roots && bvh->cut_key && bvh->node_area && bvh->child_top;
	for ( size_t i = 0; i < sizeof( scratch ) / sizeof( scratch[0] ); ++i )
	{
		*scratch[i] = sere_alloc( fn );
		ok = ok && *scratch[i] != NULL;
	}
	bvh->order = sere_alloc( sizeof( int32_t ) * (size_t) sere_pad( n ) );
	bvh->stack = sere_alloc( sizeof( build_item ) * (size_t) capacity );
	ok = ok && bvh->order && bvh->stack;
	if ( !ok )
	{
		sere_bvh_destroy( bvh );
		return SERE_ERR_MEMORY;
	}
	memcpy( bvh->tri, tri, sizeof( int32_t ) * 3 * (size_t) n );
	sere_status status = sere_bvh_build( bvh, x, y, z );
	if ( status != SERE_OK )
	{
		sere_bvh_destroy( bvh );
		return status;
	}
	*out = bvh;
	return SERE_OK;
}

void sere_bvh_destroy( sere_bvh* bvh )
{
	if ( bvh == NULL )
	{
		return;
	}
	void* arrays[] = { bvh->tri,		   bvh->nodes,		 bvh->node_level, bvh->level_nodes, bvh->level_start,
					   bvh->subtree_begin, bvh->subtree_end, bvh->cut_roots,  bvh->cut_key,		bvh->node_area,
					   bvh->lo_x,		   bvh->lo_y,		 bvh->lo_z,		  bvh->hi_x,		bvh->hi_y,
					   bvh->hi_z,		   bvh->c_x,		 bvh->c_y,		  bvh->c_z,			bvh->order,
					   bvh->stack,		   bvh->child_top };
	sere_free_all( arrays, sizeof( arrays ) / sizeof( arrays[0] ) );
	sere_free( bvh );
}

sere_status sere_bvh_set_threads( sere_bvh* bvh, int32_t threads )
{
	return bvh == NULL ? SERE_ERR_ARGUMENT : sere_threads_store( &bvh->threads, threads );
}

sere_status sere_bvh_refit( sere_bvh* bvh, const float* x, const float* y, const float* z )
{
	if ( bvh == NULL || x == NULL || y == NULL || z == NULL )
	{
		return SERE_ERR_ARGUMENT;
	}
	return refit_tree( bvh, x, y, z ) ? SERE_OK : SERE_ERR_NONFINITE;
}

double sere_bvh_quality_ratio( const sere_bvh* bvh )
{
	/* a tree of one node (8 triangles or fewer) has no nodes below its root: 0 / 0 */
	return bvh->quality_built > 0.0 ? bvh->quality / bvh->quality_built : 1.0;
}

bool sere_bvh_needs_rebuild( const sere_bvh* bvh, double threshold )
{
	return sere_bvh_quality_ratio( bvh ) > threshold;
}

sere_status sere_bvh_update( sere_bvh* bvh, const float* x, const float* y, const float* z, double threshold,
							 bool* rebuilt )
{
	sere_status status = sere_bvh_refit( bvh, x, y, z );
	bool rebuild = status == SERE_OK && sere_bvh_needs_rebuild( bvh, threshold );
	if ( rebuild )
	{
		status = sere_bvh_build( bvh, x, y, z );
	}
	if ( rebuilt != NULL )
	{
		*rebuilt = rebuild;
	}
	return status;
}

const sere_bvh_node* sere_bvh_nodes( const sere_bvh* bvh, int32_t* node_count )
{
	*node_count = bvh->node_count;
	return bvh->nodes;
}

int32_t sere_bvh_depth( const sere_bvh* bvh )
{
	return bvh->level_count;
}

const int32_t* sere_bvh_triangles( const sere_bvh* bvh, int32_t* triangle_count )
{
	*triangle_count = bvh->triangle_count;
	return bvh->tri;
}

uint64_t sere_bvh_generation( const sere_bvh* bvh )
{
	return bvh->generation;
}

int32_t sere_bvh_vertex_count( const sere_bvh* bvh )
{
	return bvh->vertex_count;
}
