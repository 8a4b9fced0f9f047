/* sere — the collision state: parameters, creation and release, the contact lists, and the closest-point queries of the
 * API. _GNU_SOURCE: sched_getaffinity for internal/team.h. */
#define _GNU_SOURCE

#include "solve/internal/collide_shared.h"

sere_collide_params sere_collide_params_default( void )
{
	sere_collide_params params = {
		/* A third of an edge of a ~4700-vertex leaf of unit width. It must stay below the mesh's
		 * smallest triangle height: past it a vertex already touches the triangle across the
		 * opposite edge of its own triangle. */
		.thickness = 0.005f,
		/* Table 2: Δt = 0.002 for every preset */
		.dt = 0.002f,
		.iterations = 8,
		/* one detection per frame, as the paper's Algorithm 1; more rounds re-query to catch
		 * contacts the push-out itself makes */
		.rounds = 1,
		.relaxation = 1.0f,
		.rebuild_ratio = SERE_BVH_REBUILD_RATIO,
	};
	return params;
}

float sere_closest_point_triangle( const float p[3], const float a[3], const float b[3], const float c[3],
								   float weights[3] )
{
	float q[3];
	return closest_point( p, a, b, c, weights, q );
}

float sere_closest_points_segments( const float p0[3], const float p1[3], const float q0[3], const float q1[3],
									float weights[2] )
{
	float d[3];
	return closest_segments( p0, p1, q0, q1, weights, d );
}

/* The arrays sized by the contact capacity, in one table for allocation and release: each holds
 * size[i] bytes per unit of capacity (the per-contact arrays of the response hold both kinds). */
#define CONTACT_ARRAYS 16

static void contact_arrays( sere_collide* c, void*** slot, size_t* size )
{
	void** slots[CONTACT_ARRAYS] = {
		(void**) &c->contacts,		(void**) &c->thread_contacts,
		(void**) &c->edge_contacts, (void**) &c->thread_edge_contacts,
		(void**) &c->entries,		(void**) &c->entry_coef,
		(void**) &c->member[0],		(void**) &c->member[1],
		(void**) &c->member[2],		(void**) &c->member[3],
		(void**) &c->contact_side,	(void**) &c->weight[0],
		(void**) &c->weight[1],		(void**) &c->weight[2],
		(void**) &c->inv_weight,	(void**) &c->corr,
	};
	size_t sizes[CONTACT_ARRAYS] = {
		sizeof( sere_contact ),		 sizeof( sere_contact ) * (size_t) ( c->slots > 1 ? c->slots - 1 : 1 ),
		sizeof( sere_edge_contact ), sizeof( sere_edge_contact ) * (size_t) c->slots,
		2 * 4 * sizeof( int32_t ),	 2 * 4 * sizeof( float ),
		2 * sizeof( int32_t ),		 2 * sizeof( int32_t ),
		2 * sizeof( int32_t ),		 2 * sizeof( int32_t ),
		2 * sizeof( float ),		 2 * sizeof( float ),
		2 * sizeof( float ),		 2 * sizeof( float ),
		2 * sizeof( float ),		 2 * 4 * sizeof( float ),
	};
	memcpy( slot, slots, sizeof( slots ) );
	memcpy( size, sizes, sizeof( sizes ) );
}

static void collide_free( sere_collide* c )
{
	if ( c->record != NULL )
	{
		for ( int t = 0; t < SERE_MAX_THREADS; ++t )
		{
			sere_free( c->record->run[t].trace.data );
		}
		sere_free( c->record->pushes );
		sere_free( c->record );
	}
	void** slot[CONTACT_ARRAYS];
	size_t size[CONTACT_ARRAYS];
	contact_arrays( c, slot, size );
	for ( int i = 0; i < CONTACT_ARRAYS; ++i )
	{
		sere_free( *slot[i] );
	}
	void* arrays[] = { c->block_thread,
					   c->block_start,
					   c->block_found,
					   c->block_work,
					   c->work_prefix,
					   c->entry_offset,
					   c->entry_cursor,
					   c->run_total,
					   c->touched,
					   c->position,
					   c->acc,
					   c->far_count,
					   c->lane_mark,
					   c->mark_offset,
					   c->mark_vertex,
					   c->mark_bits,
					   c->edge_end,
					   c->lower_edge,
					   c->owned,
					   c->edge_triangle,
					   c->push_count,
					   c->cache_x,
					   c->cache_sum,
					   c->cache_y,
					   c->cache_z,
					   c->cache_item,
					   c->cache_target,
					   c->cache_near,
					   c->cache_gap,
					   c->cache_block_thread,
					   c->cache_block_start,
					   c->cache_block_count,
					   c->cache_used,
					   c->edge_across,
					   c->rest_x,
					   c->rest_y,
					   c->rest_z };
	sere_free_all( arrays, sizeof( arrays ) / sizeof( arrays[0] ) );
}

/* (Re)allocates the arrays sized by the contact capacity; the old ones are kept on failure. */
static sere_status alloc_contacts( sere_collide* c, int32_t capacity )
{
	void** slot[CONTACT_ARRAYS];
	size_t size[CONTACT_ARRAYS];
	contact_arrays( c, slot, size );
	void* fresh[CONTACT_ARRAYS] = { NULL };
	bool ok = true;
	for ( int i = 0; i < CONTACT_ARRAYS; ++i )
	{
		fresh[i] = sere_alloc( size[i] * (size_t) sere_pad( capacity ) );
		ok = ok && fresh[i] != NULL;
	}
	for ( int i = 0; i < CONTACT_ARRAYS; ++i )
	{
		sere_free( ok ? *slot[i] : fresh[i] );
		*slot[i] = ok ? fresh[i] : *slot[i];
	}
	if ( !ok )
	{
		return SERE_ERR_MEMORY;
	}
	c->capacity = capacity;
	c->state += 1;
	c->contact_count = 0;
	c->edge_contact_count = 0;
	c->touched_count = 0;
	return SERE_OK;
}

/* Builds the sorted neighbour lists of the mesh's edges (each edge appears in two triangles at
 * most, so a vertex has at most 2 × its triangle count neighbours before duplicates go). */
static void build_neighbors( sere_collide* c, const int32_t* tri, int32_t triangles, int32_t* offset,
							 int32_t* neighbor )
{
	int32_t n = c->vertex_count;
	memset( offset, 0, sizeof( int32_t ) * ( (size_t) n + 1 ) );
	for ( int32_t t = 0; t < triangles; ++t )
	{
		for ( int r = 0; r < 3; ++r )
		{
			offset[tri[3 * t + r] + 1] += 2;
		}
	}
	for ( int32_t i = 0; i < n; ++i )
	{
		offset[i + 1] += offset[i];
	}
	/* fill each list, then sort it and drop repeats in place */
	int32_t* cursor = c->entry_cursor;
	for ( int32_t i = 0; i < n; ++i )
	{
		cursor[i] = offset[i];
	}
	for ( int32_t t = 0; t < triangles; ++t )
	{
		const int32_t* v = tri + 3 * (size_t) t;
		for ( int r = 0; r < 3; ++r )
		{
			int32_t a = v[r];
			neighbor[cursor[a]++] = v[( r + 1 ) % 3];
			neighbor[cursor[a]++] = v[( r + 2 ) % 3];
		}
	}
	int32_t write = 0;
	for ( int32_t i = 0; i < n; ++i )
	{
		int32_t begin = offset[i], end = offset[i + 1];
		offset[i] = write;
		/* insertion sort: lists are a dozen entries long */
		for ( int32_t k = begin + 1; k < end; ++k )
		{
			int32_t value = neighbor[k], j = k;
			while ( j > begin && neighbor[j - 1] > value )
			{
				neighbor[j] = neighbor[j - 1];
				--j;
			}
			neighbor[j] = value;
		}
		for ( int32_t k = begin; k < end; ++k )
		{
			if ( write == offset[i] || neighbor[write - 1] != neighbor[k] )
			{
				neighbor[write++] = neighbor[k];
			}
		}
	}
	offset[n] = write;
}

/* Adds bits to vertex j's scratch marks, listing j at its first bit; returns the list's length. */
static int32_t list_mark( sere_collide* c, lane_bits* scratch, int32_t j, uint32_t bits, int32_t used )
{
	if ( scratch[j] == 0 )
	{
		c->mark_vertex[used++] = j;
	}
	scratch[j] = (lane_bits) ( scratch[j] | bits );
	return used;
}

/* The lane marks of every query group, from the neighbour lists (lane_bits). Listed once per
 * group, merged, the marks cost one plain store per vertex to set and one to clear; set from the
 * neighbour lists at every query, a vertex shared by several lanes took a read-modify-write per
 * lane, each waiting on the last. */
static bool build_marks( sere_collide* c, const int32_t* neighbor_offset, const int32_t* neighbor )
{
	int32_t n = c->vertex_count;
	int32_t groups = ( n + SERE_BVH_WIDTH - 1 ) / SERE_BVH_WIDTH;
	c->mark_offset = sere_alloc( sizeof( int32_t ) * ( (size_t) groups + 1 ) );
	/* a group lists each of its vertices and their neighbours once at most: over all groups,
	 * n vertices and neighbor_offset[n] neighbour entries */
	size_t most = (size_t) n + (size_t) neighbor_offset[n] + 1;
	c->mark_vertex = sere_alloc( sizeof( int32_t ) * most );
	c->mark_bits = sere_alloc( sizeof( lane_bits ) * most );
	if ( c->mark_offset == NULL || c->mark_vertex == NULL || c->mark_bits == NULL )
	{
		return false;
	}
	/* thread 0's lane marks, zero, as scratch: zero again on return */
	lane_bits* scratch = c->lane_mark;
	int32_t used = 0;
	for ( int32_t g = 0; g < groups; ++g )
	{
		int32_t first = g * SERE_BVH_WIDTH, begin = used;
		int32_t count = n - first < SERE_BVH_WIDTH ? n - first : SERE_BVH_WIDTH;
		c->mark_offset[g] = begin;
		for ( int32_t k = 0; k < count; ++k )
		{
			int32_t i = first + k;
			uint32_t near = 1u << k;
			used = list_mark( c, scratch, i, near | near << 8, used );
			for ( int32_t e = neighbor_offset[i]; e < neighbor_offset[i + 1]; ++e )
			{
				used = list_mark( c, scratch, neighbor[e], near, used );
			}
		}
		for ( int32_t e = begin; e < used; ++e )
		{
			c->mark_bits[e] = scratch[c->mark_vertex[e]];
			scratch[c->mark_vertex[e]] = 0;
		}
	}
	c->mark_offset[groups] = used;
	return true;
}

/* The edge list and each triangle's owned edges (see sere_collide.edge_end) from the sorted
 * neighbour lists: vertex a's neighbours above a are the edges it is the lower end of, in order.
 * A triangle with a repeated corner owns no edge between the two (it has no length). */
static bool build_edges( sere_collide* c, const int32_t* tri, const int32_t* neighbor_offset, const int32_t* neighbor )
{
	int32_t n = c->vertex_count, triangles = c->triangle_count;
	int32_t* first = c->lower_edge = sere_alloc( sizeof( int32_t ) * ( (size_t) n + 1 ) );
	if ( first == NULL )
	{
		return false;
	}
	int32_t edges = 0;
	for ( int32_t a = 0; a < n; ++a )
	{
		first[a] = edges;
		for ( int32_t e = neighbor_offset[a]; e < neighbor_offset[a + 1]; ++e )
		{
			edges += neighbor[e] > a;
		}
	}
	first[n] = edges;
	c->edge_count = edges;
	c->edge_end = sere_alloc( sizeof( int32_t ) * ( 2 * (size_t) edges + 1 ) );
	c->owned = sere_alloc( sizeof( int32_t ) * ( 3 * (size_t) triangles + 1 ) );
	c->edge_triangle = sere_alloc( sizeof( int32_t ) * ( (size_t) edges + 1 ) );
	uint8_t* seen = sere_alloc( (size_t) edges + 1 );
	bool ok = c->edge_end != NULL && c->owned != NULL && c->edge_triangle != NULL && seen != NULL;
	for ( int32_t a = 0; ok && a < n; ++a )
	{
		int32_t e = first[a];
		for ( int32_t k = neighbor_offset[a]; k < neighbor_offset[a + 1]; ++k )
		{
			if ( neighbor[k] > a )
			{
				c->edge_end[2 * e] = a, c->edge_end[2 * e + 1] = neighbor[k];
				e += 1;
			}
		}
	}
	for ( int32_t t = 0; ok && t < triangles; ++t )
	{
		for ( int r = 0; r < 3; ++r )
		{
			int32_t i = tri[3 * t + r], j = tri[3 * t + ( r + 1 ) % 3];
			int32_t a = i < j ? i : j, b = i < j ? j : i;
			int32_t edge = -1;
			/* the neighbours above a are sorted: find b among them */
			for ( int32_t e = first[a]; a != b && e < first[a + 1] && edge < 0; ++e )
			{
				edge = c->edge_end[2 * e + 1] == b ? e : -1;
			}
			c->owned[3 * t + r] = edge >= 0 && !seen[edge] ? edge : -1;
			if ( edge >= 0 && !seen[edge] )
			{
				seen[edge] = 1;
				c->edge_triangle[edge] = t;
			}
		}
	}
	sere_free( seen );
	return ok;
}

/* (Re)allocates the per-thread arrays for `slots` threads (and the contact arrays, whose
 * per-thread parts they size, once a capacity is set); the old ones are kept on failure. The
 * candidate list is dropped: its runs are per thread. */
static sere_status alloc_slots( sere_collide* c, int32_t slots )
{
	size_t vn = (size_t) sere_pad( c->vertex_count ), listed = (size_t) c->cache_capacity * (size_t) slots;
	void** field[] = { (void**) &c->entry_cursor, (void**) &c->run_total,  (void**) &c->far_count,
					   (void**) &c->lane_mark,	  (void**) &c->cache_item, (void**) &c->cache_target,
					   (void**) &c->cache_near,	  (void**) &c->cache_gap,  (void**) &c->cache_used };
	size_t bytes[] = { sizeof( int32_t ) * vn * (size_t) slots,
					   sizeof( int32_t ) * 2 * FAR_STRIDE * (size_t) slots,
					   sizeof( int32_t ) * FAR_STRIDE * (size_t) slots,
					   sizeof( lane_bits ) * vn * (size_t) slots,
					   sizeof( int32_t ) * listed,
					   sizeof( int32_t ) * listed,
					   listed,
					   sizeof( float ) * listed,
					   sizeof( int32_t ) * FAR_STRIDE * (size_t) slots };
	enum
	{
		FIELDS = sizeof( field ) / sizeof( field[0] )
	};
	void* fresh[FIELDS];
	bool ok = true;
	for ( int i = 0; i < FIELDS; ++i )
	{
		fresh[i] = sere_alloc( bytes[i] );
		ok = ok && fresh[i] != NULL;
	}
	int32_t old = c->slots;
	c->slots = slots;
	ok = ok && ( c->capacity == 0 || alloc_contacts( c, c->capacity ) == SERE_OK );
	c->slots = ok ? slots : old;
	for ( int i = 0; i < FIELDS; ++i )
	{
		sere_free( ok ? *field[i] : fresh[i] );
		*field[i] = ok ? fresh[i] : *field[i];
	}
	c->cache_valid = false;
	c->state += 1;
	return ok ? SERE_OK : SERE_ERR_MEMORY;
}

/* Contacts of each kind stay below this: the gather lists index 4 entries per contact of both
 * kinds with int32_t. */
#define CAPACITY_LIMIT ( 1 << 28 )

sere_status sere_collide_create( const sere_bvh* bvh, int32_t contact_capacity, sere_collide** out )
{
	if ( out == NULL )
	{
		return SERE_ERR_ARGUMENT;
	}
	*out = NULL;
	if ( bvh == NULL || contact_capacity < 0 || contact_capacity >= CAPACITY_LIMIT )
	{
		return SERE_ERR_ARGUMENT;
	}
	int32_t n = sere_bvh_vertex_count( bvh );
	int32_t triangles;
	const int32_t* tri = sere_bvh_triangles( bvh, &triangles );
	int64_t capacity = contact_capacity > 0 ? contact_capacity : 8 * (int64_t) n;
	capacity = capacity < CAPACITY_LIMIT - 1 ? capacity : CAPACITY_LIMIT - 1;
	sere_collide* c = sere_alloc( sizeof( sere_collide ) );
	if ( c == NULL )
	{
		return SERE_ERR_MEMORY;
	}
	c->vertex_count = n;
	c->triangle_count = triangles;
	c->cache_capacity = CACHE_PAIRS * n + DETECT_BLOCK;
	/* Slots for OpenMP's count now; sere_collide_set_threads makes more. */
	int32_t slots = omp_get_max_threads() < SERE_MAX_THREADS ? omp_get_max_threads() : SERE_MAX_THREADS;
	size_t vn = (size_t) sere_pad( n );
	c->entry_offset = sere_alloc( sizeof( int32_t ) * ( vn + 1 ) );
	c->touched = sere_alloc( sizeof( int32_t ) * vn );
	c->position = sere_alloc( 4 * sizeof( float ) * vn );
	c->acc = sere_alloc( 4 * sizeof( float ) * vn );
	c->push_count = sere_alloc( sizeof( float ) * vn );
	bool ok =
		c->entry_offset && c->touched && c->position && c->acc && c->push_count && alloc_slots( c, slots ) == SERE_OK;
	/* the mesh's edges as sorted neighbour lists, needed only to list the edges and build the
	 * mark lists (thread 0's lane marks serve as scratch) */
	int32_t* neighbor_offset = sere_alloc( sizeof( int32_t ) * ( vn + 1 ) );
	int32_t* neighbor = sere_alloc( sizeof( int32_t ) * ( 6 * (size_t) triangles + 1 ) );
	ok = ok && neighbor_offset && neighbor;
	if ( ok )
	{
		build_neighbors( c, tri, triangles, neighbor_offset, neighbor );
		ok = build_edges( c, tri, neighbor_offset, neighbor ) && build_marks( c, neighbor_offset, neighbor );
	}
	sere_free( neighbor_offset );
	sere_free( neighbor );
	c->vertex_blocks = ( n + DETECT_BLOCK - 1 ) / DETECT_BLOCK;
	c->block_count = 2 * c->vertex_blocks;
	size_t blocks = (size_t) c->block_count + 1;
	c->block_thread = sere_alloc( sizeof( int32_t ) * blocks );
	c->block_start = sere_alloc( sizeof( int32_t ) * blocks );
	c->block_found = sere_alloc( sizeof( int64_t ) * blocks );
	c->block_work = sere_alloc( sizeof( int64_t ) * blocks );
	c->work_prefix = sere_alloc( sizeof( int64_t ) * blocks );
	ok = ok && c->block_thread && c->block_start && c->block_found && c->block_work && c->work_prefix;
	c->skin = SKIN;
	c->edge_across = sere_alloc( 3 * sizeof( float ) * (size_t) sere_pad( c->edge_count > 0 ? c->edge_count : 1 ) );
	c->cache_x = sere_alloc( sizeof( float ) * vn );
	c->cache_y = sere_alloc( sizeof( float ) * vn );
	c->cache_z = sere_alloc( sizeof( float ) * vn );
	c->cache_sum = sere_alloc( 4 * sizeof( double ) * blocks );
	c->cache_block_thread = sere_alloc( sizeof( int32_t ) * blocks );
	c->cache_block_start = sere_alloc( sizeof( int32_t ) * blocks );
	c->cache_block_count = sere_alloc( sizeof( int32_t ) * blocks );
	ok = ok && c->cache_x && c->cache_y && c->cache_z && c->cache_sum && c->cache_block_thread &&
		 c->cache_block_start && c->cache_block_count && c->edge_across;
	if ( !ok || alloc_contacts( c, (int32_t) capacity ) != SERE_OK )
	{
		collide_free( c );
		sere_free( c );
		return SERE_ERR_MEMORY;
	}
	*out = c;
	return SERE_OK;
}

void sere_collide_destroy( sere_collide* collide )
{
	if ( collide == NULL )
	{
		return;
	}
	collide_free( collide );
	sere_free( collide );
}

sere_status sere_collide_set_threads( sere_collide* collide, int32_t threads )
{
	if ( collide == NULL || !sere_threads_valid( threads ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	if ( threads > collide->slots )
	{
		sere_status status = alloc_slots( collide, threads );
		if ( status != SERE_OK )
		{
			return status;
		}
	}
	collide->threads = threads;
	return SERE_OK;
}

sere_status sere_collide_reserve( sere_collide* collide, int32_t contact_capacity )
{
	if ( collide == NULL || contact_capacity < 1 || contact_capacity >= CAPACITY_LIMIT )
	{
		return SERE_ERR_ARGUMENT;
	}
	if ( contact_capacity <= collide->capacity )
	{
		return SERE_OK;
	}
	return alloc_contacts( collide, contact_capacity );
}

sere_status sere_collide_set_rest( sere_collide* collide, const float* x, const float* y, const float* z )
{
	if ( collide == NULL || ( x == NULL ) != ( y == NULL ) || ( x == NULL ) != ( z == NULL ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	int32_t n = collide->vertex_count;
	collide->state += 1;
	if ( x == NULL )
	{
		sere_free( collide->rest_x ), sere_free( collide->rest_y ), sere_free( collide->rest_z );
		collide->rest_x = collide->rest_y = collide->rest_z = NULL;
		return SERE_OK;
	}
	for ( int32_t i = 0; i < n; ++i )
	{
		if ( !isfinite( x[i] ) || !isfinite( y[i] ) || !isfinite( z[i] ) )
		{
			return SERE_ERR_NONFINITE;
		}
	}
	size_t bytes = sizeof( float ) * (size_t) sere_pad( n > 0 ? n : 1 );
	float* rest[3] = { collide->rest_x, collide->rest_y, collide->rest_z };
	for ( int a = 0; a < 3; ++a )
	{
		rest[a] = rest[a] != NULL ? rest[a] : sere_alloc( bytes );
	}
	collide->rest_x = rest[0], collide->rest_y = rest[1], collide->rest_z = rest[2];
	if ( rest[0] == NULL || rest[1] == NULL || rest[2] == NULL )
	{
		sere_free( rest[0] ), sere_free( rest[1] ), sere_free( rest[2] );
		collide->rest_x = collide->rest_y = collide->rest_z = NULL;
		return SERE_ERR_MEMORY;
	}
	memcpy( rest[0], x, sizeof( float ) * (size_t) n );
	memcpy( rest[1], y, sizeof( float ) * (size_t) n );
	memcpy( rest[2], z, sizeof( float ) * (size_t) n );
	return SERE_OK;
}

int32_t sere_collide_list_uses( const sere_collide* collide )
{
	return collide->cache_uses;
}

void sere_collide_drop_list( sere_collide* collide )
{
	collide->cache_valid = false;
	collide->cache_uses = 0;
}

const sere_contact* sere_collide_contacts( const sere_collide* collide, int32_t* count )
{
	*count = collide->contact_count;
	return collide->contacts;
}

const sere_edge_contact* sere_collide_edge_contacts( const sere_collide* collide, int32_t* count )
{
	*count = collide->edge_contact_count;
	return collide->edge_contacts;
}
