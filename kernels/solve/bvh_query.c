/* sere — the BVH's queries: a box against every node's eight lane boxes at once (simd.h's groups
 * of eight), a group of eight query boxes against a node, and the point query built on them.
 * _GNU_SOURCE: sched_getaffinity for internal/team.h. */
#define _GNU_SOURCE

#include "solve/internal/bvh_shared.h"

#include <math.h>
#include <string.h>

/* A query box, each face splat across the eight lanes of a node. */
typedef struct query_box
{
	sere_v8 lx, ly, lz, hx, hy, hz;
} query_box;

static inline query_box query_make( const float lo[3], const float hi[3] )
{
	query_box q = { sere_v8_splat( lo[0] ), sere_v8_splat( lo[1] ), sere_v8_splat( lo[2] ),
					sere_v8_splat( hi[0] ), sere_v8_splat( hi[1] ), sere_v8_splat( hi[2] ) };
	return q;
}

/* Lanes where [min, max] overlaps [lo, hi] on one axis. */
static inline sere_m8 axis_overlap( sere_v8 min, sere_v8 max, sere_v8 lo, sere_v8 hi )
{
	return sere_m8_and( sere_v8_le( min, hi ), sere_v8_ge( max, lo ) );
}

/* Bit k set when lane k's box overlaps the query box; empty lanes (+inf, −inf) never do. */
static inline uint32_t overlap_mask( const sere_bvh_node* node, const query_box* q )
{
	sere_m8 x = axis_overlap( sere_v8_load( node->min_x ), sere_v8_load( node->max_x ), q->lx, q->hx );
	sere_m8 y = axis_overlap( sere_v8_load( node->min_y ), sere_v8_load( node->max_y ), q->ly, q->hy );
	sere_m8 z = axis_overlap( sere_v8_load( node->min_z ), sere_v8_load( node->max_z ), q->lz, q->hz );
	return sere_m8_bits( sere_m8_and( x, sere_m8_and( y, z ) ) );
}

void sere_bvh_query_box( const sere_bvh* bvh, const float lo[3], const float hi[3], sere_bvh_visit_fn* visit,
						 void* context )
{
	for ( int a = 0; a < 3; ++a )
	{
		if ( !( isfinite( lo[a] ) && isfinite( hi[a] ) ) )
		{
			return;
		}
	}
	query_box q = query_make( lo, hi );
	int32_t stack[STACK_SIZE];
	int32_t size = 0;
	stack[size++] = 0;
	while ( size > 0 )
	{
		const sere_bvh_node* node = bvh->nodes + stack[--size];
		uint32_t mask = overlap_mask( node, &q );
		while ( mask != 0 )
		{
			int k = __builtin_ctz( mask );
			mask &= mask - 1;
			int32_t c = node->child[k];
			if ( c >= 0 )
			{
				stack[size++] = c;
			}
			else
			{
				visit( context, ~c );
			}
		}
	}
}

/* The group's lane boxes, one group of eight per face. */
typedef query_box group_box;

/* Bit k set when the box [lo, hi] overlaps group lane k (ignored lanes hold empty boxes). */
static inline uint32_t group_mask( const group_box* lanes, float lx, float ly, float lz, float hx, float hy, float hz )
{
	sere_m8 x = axis_overlap( sere_v8_splat( lx ), sere_v8_splat( hx ), lanes->lx, lanes->hx );
	sere_m8 y = axis_overlap( sere_v8_splat( ly ), sere_v8_splat( hy ), lanes->ly, lanes->hy );
	sere_m8 z = axis_overlap( sere_v8_splat( lz ), sere_v8_splat( hz ), lanes->lz, lanes->hz );
	return sere_m8_bits( sere_m8_and( x, sere_m8_and( y, z ) ) );
}

static inline group_box group_lanes( float lo[3][SERE_BVH_WIDTH], float hi[3][SERE_BVH_WIDTH] )
{
	group_box q = { sere_v8_load( lo[0] ), sere_v8_load( lo[1] ), sere_v8_load( lo[2] ),
					sere_v8_load( hi[0] ), sere_v8_load( hi[1] ), sere_v8_load( hi[2] ) };
	return q;
}

/* Bit k set when child k of the node is negative: a triangle, or SERE_BVH_EMPTY, whose empty
 * box no query overlaps. */
static inline uint32_t leaf_mask( const sere_bvh_node* node )
{
	uint32_t mask = 0;
	for ( int k = 0; k < SERE_BVH_WIDTH; ++k )
	{
		mask |= (uint32_t) ( node->child[k] < 0 ) << k;
	}
	return mask;
}

/* Bit k set when child k of node n holds a triangle with a corner index above floor. */
static inline uint32_t above_mask( const sere_bvh* bvh, int32_t n, int32_t floor )
{
	const int32_t* top = bvh->child_top + (size_t) n * SERE_BVH_WIDTH;
	uint32_t mask = 0;
	for ( int k = 0; k < SERE_BVH_WIDTH; ++k )
	{
		mask |= (uint32_t) ( top[k] > floor ) << k;
	}
	return mask;
}

/* The end of a node's visit, the same for every walk: node's live children (bits of live) are taken,
 * the inner ones pushed on the stack and the leaves visited in child order with their lanes (hits,
 * or the trace's next byte when replaying); with a trace the node and its leaves are counted, and
 * recorded unless replaying. Returns the new stack size. */
static inline int32_t descend( const sere_bvh_node* node, uint32_t live, const uint32_t* hits, sere_bvh_trace* trace,
							   bool replay, int32_t* stack, int32_t size, sere_bvh_visit_group_fn* visit,
							   void* context )
{
	uint32_t leaves = live & leaf_mask( node ), inner = live & ~leaves;
	if ( trace != NULL )
	{
		trace->nodes += 1;
		if ( !replay )
		{
			sere_bvh_trace_put( trace, live );
		}
	}
	while ( inner != 0 )
	{
		stack[size++] = node->child[__builtin_ctz( inner )];
		inner &= inner - 1;
	}
	while ( leaves != 0 )
	{
		int k = __builtin_ctz( leaves );
		leaves &= leaves - 1;
		uint32_t lanes = replay ? sere_bvh_trace_take( trace ) : hits[k];
		if ( trace != NULL )
		{
			trace->leaves += 1;
			if ( !replay )
			{
				sere_bvh_trace_put( trace, lanes );
			}
		}
		visit( context, ~node->child[k], lanes );
	}
	return size;
}

/* The floor's walk (sere_bvh_trace replaying): the nodes and visits recorded in trace, in their order, each
 * opened node's boxes (and, above, its child_top entries) loaded and added up. */
static inline void replay_group( const sere_bvh* bvh, bool above, sere_bvh_trace* trace, sere_bvh_visit_group_fn* visit,
								 void* context )
{
	if ( sere_bvh_trace_take( trace ) == 0 )
	{
		return;
	}
	sere_v8 sum = sere_v8_zero();
	int32_t top_sum = 0;
	int32_t stack[STACK_SIZE];
	int32_t size = 0;
	stack[size++] = 0;
	while ( size > 0 )
	{
		int32_t index = stack[--size];
		const sere_bvh_node* node = bvh->nodes + index;
		sum = sere_v8_add( sum, sere_v8_add( sere_v8_add( sere_v8_load( node->min_x ), sere_v8_load( node->min_y ) ),
											 sere_v8_load( node->min_z ) ) );
		sum = sere_v8_add( sum, sere_v8_add( sere_v8_add( sere_v8_load( node->max_x ), sere_v8_load( node->max_y ) ),
											 sere_v8_load( node->max_z ) ) );
		if ( above )
		{
			const int32_t* top = bvh->child_top + (size_t) index * SERE_BVH_WIDTH;
			for ( int k = 0; k < SERE_BVH_WIDTH; ++k )
			{
				top_sum += top[k];
			}
		}
		uint32_t live = sere_bvh_trace_take( trace );
		size = descend( node, live, NULL, trace, true, stack, size, visit, context );
	}
	float lanes[4];
	sere_v4_store( lanes, sere_v4_add( sere_v8_low( sum ), sere_v8_high( sum ) ) );
	trace->sink += ( lanes[0] + lanes[1] ) + ( lanes[2] + lanes[3] );
	trace->isink += top_sum;
}

/* sere_bvh_query_group, or sere_bvh_query_group_above when above, recording the walk into trace
 * unless it is NULL (inlined with constants, so the plain query carries neither an index test nor
 * a record). */
static inline void query_group( const sere_bvh* bvh, const sere_bvh_group* group, bool above, int32_t floor,
								sere_bvh_trace* trace, sere_bvh_visit_group_fn* visit, void* context )
{
	/* the lanes as given, ignored ones emptied, and their union for the walk down */
	float lo[3][SERE_BVH_WIDTH], hi[3][SERE_BVH_WIDTH];
	float ulo[3] = { INFINITY, INFINITY, INFINITY }, uhi[3] = { -INFINITY, -INFINITY, -INFINITY };
	const float* glo[3] = { group->lo_x, group->lo_y, group->lo_z };
	const float* ghi[3] = { group->hi_x, group->hi_y, group->hi_z };
	for ( int k = 0; k < SERE_BVH_WIDTH; ++k )
	{
		bool used = k < group->count;
		for ( int a = 0; a < 3; ++a )
		{
			used = used && isfinite( glo[a][k] ) && isfinite( ghi[a][k] );
		}
		for ( int a = 0; a < 3; ++a )
		{
			lo[a][k] = used ? glo[a][k] : INFINITY;
			hi[a][k] = used ? ghi[a][k] : -INFINITY;
			ulo[a] = sere_min_x86( ulo[a], lo[a][k] );
			uhi[a] = sere_max_x86( uhi[a], hi[a][k] );
		}
	}
	bool walk = ulo[0] <= uhi[0] && ulo[1] <= uhi[1] && ulo[2] <= uhi[2];
	if ( trace != NULL )
	{
		sere_bvh_trace_put( trace, walk );
	}
	if ( !walk )
	{
		return;
	}
	query_box q = query_make( ulo, uhi );
	group_box lanes = group_lanes( lo, hi );
	int32_t stack[STACK_SIZE];
	int32_t size = 0;
	stack[size++] = 0;
	while ( size > 0 )
	{
		int32_t index = stack[--size];
		const sere_bvh_node* node = bvh->nodes + index;
		/* Each child inside the union is tested against the eight lanes: a child inside the union
		 * can still miss every lane (the union of eight cubes along a curve of vertices is mostly
		 * empty space), and skipping such subtrees saved 14% of the flat maple's detection and 9%
		 * of the dried one's. Which children any lane hits is gathered as bits first and only then
		 * acted on: half the children inside the union miss every lane, and a branch on each one
		 * mispredicted as often as not (without it the dried maple's detection took 7% longer on
		 * one thread). The children pushed here are popped only after this node's leaves are
		 * visited, so the visits come in the same order as when each child was handled in turn. */
		uint32_t mask = overlap_mask( node, &q );
		if ( above )
		{
			mask &= above_mask( bvh, index, floor );
		}
		uint32_t hits[SERE_BVH_WIDTH];
		uint32_t live = 0;
		while ( mask != 0 )
		{
			int k = __builtin_ctz( mask );
			mask &= mask - 1;
			hits[k] = group_mask( &lanes, node->min_x[k], node->min_y[k], node->min_z[k], node->max_x[k],
								  node->max_y[k], node->max_z[k] );
			live |= (uint32_t) ( hits[k] != 0 ) << k;
		}
		size = descend( node, live, hits, trace, false, stack, size, visit, context );
	}
}

void sere_bvh_query_group( const sere_bvh* bvh, const sere_bvh_group* group, sere_bvh_visit_group_fn* visit,
						   void* context )
{
	query_group( bvh, group, false, 0, NULL, visit, context );
}

void sere_bvh_query_group_above( const sere_bvh* bvh, const sere_bvh_group* group, int32_t floor,
								 sere_bvh_visit_group_fn* visit, void* context )
{
	query_group( bvh, group, true, floor, NULL, visit, context );
}

void sere_bvh_query_group_traced( const sere_bvh* bvh, const sere_bvh_group* group, bool above, int32_t floor,
								  sere_bvh_trace* trace, sere_bvh_visit_group_fn* visit, void* context )
{
	if ( trace->replay )
	{
		above ? replay_group( bvh, true, trace, visit, context ) : replay_group( bvh, false, trace, visit, context );
	}
	else if ( above )
	{
		query_group( bvh, group, true, floor, trace, visit, context );
	}
	else
	{
		query_group( bvh, group, false, 0, trace, visit, context );
	}
}

bool sere_bvh_trace_grow( sere_bvh_trace* trace )
{
	int64_t capacity = trace->capacity > 0 ? 2 * trace->capacity : 1 << 16;
	uint8_t* data = sere_alloc( (size_t) capacity );
	if ( data == NULL )
	{
		return false;
	}
	if ( trace->size > 0 )
	{
		memcpy( data, trace->data, (size_t) trace->size );
	}
	sere_free( trace->data );
	trace->data = data;
	trace->capacity = capacity;
	return true;
}

typedef struct collect_context
{
	int32_t* out;
	int32_t capacity;
	int32_t count;
} collect_context;

static void collect( void* context, int32_t triangle )
{
	collect_context* c = context;
	if ( c->count < c->capacity )
	{
		c->out[c->count] = triangle;
	}
	c->count += 1;
}

int32_t sere_bvh_query( const sere_bvh* bvh, float x, float y, float z, float r, int32_t* out, int32_t capacity )
{
	float lo[3] = { x - r, y - r, z - r }, hi[3] = { x + r, y + r, z + r };
	collect_context c = { out, capacity, 0 };
	sere_bvh_query_box( bvh, lo, hi, collect, &c );
	return c.count;
}
