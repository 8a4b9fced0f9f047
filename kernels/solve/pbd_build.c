/* sere — building the PBD solver (Jeong et al.; Müller et al. 2007): particles in breadth-first
 * order cut into bands, constraints colored and packed into lanes, the Jacobi adjacency; the rest
 * lengths and compliance weights; the predict and finish steps around the projection.
 * _GNU_SOURCE: sched_getaffinity for internal/team.h. */
#define _GNU_SOURCE

#include "core/array.h"
#include "solve/internal/pbd_shared.h"

#include <float.h>
#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

/* ---------------------------------------------------------------------------------------
 * Create: particle order, bands, lane layout. */

/* Breadth-first search from start over the particle graph; appends the visited particles to
 * order (from *count on) and marks them with tag. */
static void breadth_first( int32_t start, const int32_t* offset, const int32_t* neighbor, int32_t* mark, int32_t tag,
						   int32_t* order, int32_t* count )
{
	int32_t head = *count;
	mark[start] = tag;
	order[( *count )++] = start;
	while ( head < *count )
	{
		int32_t i = order[head++];
		for ( int32_t e = offset[i]; e < offset[i + 1]; ++e )
		{
			int32_t j = neighbor[e];
			if ( mark[j] != tag )
			{
				mark[j] = tag;
				order[( *count )++] = j;
			}
		}
	}
}

/* Particles in breadth-first order, each connected component from a pseudo-peripheral
 * particle (the last one reached from its lowest index): the order then sweeps across the
 * mesh in levels, each constraint joins equal or adjacent levels, and a range of the order is
 * a band whose boundary with the next range is short. */
static sere_status order_particles( const int32_t* a, const int32_t* b, int32_t count, int32_t n, int32_t* order )
{
	int32_t* offset = calloc( (size_t) n + 1, sizeof( int32_t ) );
	int32_t* neighbor = malloc( sizeof( int32_t ) * 2 * (size_t) count );
	int32_t* fill = malloc( sizeof( int32_t ) * (size_t) n );
	int32_t* mark = malloc( sizeof( int32_t ) * (size_t) n );
	if ( offset == NULL || neighbor == NULL || fill == NULL || mark == NULL )
	{
		free( offset ), free( neighbor ), free( fill ), free( mark );
		return SERE_ERR_MEMORY;
	}
	for ( int32_t k = 0; k < count; ++k )
	{
		offset[a[k] + 1] += 1;
		offset[b[k] + 1] += 1;
	}
	for ( int32_t i = 0; i < n; ++i )
	{
		offset[i + 1] += offset[i];
		mark[i] = -1;
	}
	memcpy( fill, offset, sizeof( int32_t ) * (size_t) n );
	for ( int32_t k = 0; k < count; ++k )
	{
		neighbor[fill[a[k]]++] = b[k];
		neighbor[fill[b[k]]++] = a[k];
	}
	int32_t placed = 0, components = 0;
	for ( int32_t i = 0; i < n; ++i )
	{
		if ( mark[i] >= 0 )
		{
			continue;
		}
		/* Probe from i (written past the placed prefix, then overwritten), keep its last. */
		int32_t probe = placed;
		breadth_first( i, offset, neighbor, mark, 2 * components, order, &probe );
		int32_t far = order[probe - 1];
		breadth_first( far, offset, neighbor, mark, 2 * components + 1, order, &placed );
		components += 1;
	}
	free( offset ), free( neighbor ), free( fill ), free( mark );
	return SERE_OK;
}

/* Cuts the n slots into R bands, start[0..R], each holding about the same share of the
 * constraint ends (ends[s]: ends in slots before s), so that threads get equal work (bands of
 * equal particle counts differed by 9% in constraints on the maple); the bounds sit on
 * multiples of 4 slots (a 64-byte line of records), so two bands never share a cache line.
 * Returns 0 when one of several bands would be empty or some constraint joins two bands that are not
 * neighbors (bands thinner than a breadth-first level). */
static int assign_bands( int32_t bands, int32_t n, const int32_t* ends, const int32_t* a, const int32_t* b,
						 int32_t count, const int32_t* slot, int32_t* start, int32_t* band_of_slot )
{
	start[0] = 0, start[bands] = n;
	int32_t s = 0;
	for ( int32_t r = 1; r < bands; ++r )
	{
		const int64_t target = (int64_t) ends[n] * r / bands;
		while ( ends[s] < target )
		{
			s += 1;
		}
		start[r] = s & ~3;
	}
	for ( int32_t r = 0; r < bands; ++r )
	{
		if ( start[r + 1] <= start[r] && bands > 1 )
		{
			return 0;
		}
		for ( int32_t q = start[r]; q < start[r + 1]; ++q )
		{
			band_of_slot[q] = r;
		}
	}
	for ( int32_t k = 0; k < count; ++k )
	{
		int32_t ra = band_of_slot[slot[a[k]]], rb = band_of_slot[slot[b[k]]];
		if ( ra - rb > 1 || rb - ra > 1 )
		{
			return 0;
		}
	}
	return 1;
}

/* The per-lane arrays for pbd->lanes lanes and the per-slot records (n particles rounded up to
 * 4, then a dummy pair per item); false when one is missing. */
static bool alloc_lanes( sere_pbd* pbd, int32_t n )
{
	const size_t lanes = (size_t) pbd->lanes;
	pbd->ia = sere_alloc( sizeof( int32_t ) * lanes );
	pbd->ib = sere_alloc( sizeof( int32_t ) * lanes );
	pbd->source = sere_alloc( sizeof( int32_t ) * lanes );
	pbd->rest = sere_alloc( sizeof( float ) * lanes );
	pbd->lambda = sere_alloc( sizeof( float ) * lanes );
	pbd->weight = sere_alloc( sizeof( float ) * lanes );
	pbd->factor = sere_alloc( sizeof( float ) * lanes );
	pbd->slot_count = ( ( n + 3 ) & ~3 ) + 4 * pbd->items;
	pbd->push = sere_alloc( sizeof( float ) * (size_t) pbd->slot_count );
	pbd->residual_partial = sere_alloc( sizeof( double ) * 4 * (size_t) ( n / RESIDUAL_BLOCK + 1 ) );
	pbd->packed[0] = sere_alloc( sizeof( float ) * 4 * (size_t) pbd->slot_count );
	pbd->packed[1] = sere_alloc( sizeof( float ) * 4 * (size_t) pbd->slot_count );
	for ( int h = 0; h < 2; ++h )
	{
		pbd->history[h] = sere_alloc( sizeof( float ) * 4 * (size_t) pbd->slot_count );
		pbd->lambda_history[h] = sere_alloc( sizeof( float ) * lanes );
	}
	return pbd->ia && pbd->ib && pbd->source && pbd->rest && pbd->lambda && pbd->weight && pbd->factor && pbd->push &&
		   pbd->residual_partial && pbd->packed[0] && pbd->packed[1] && pbd->history[0] && pbd->history[1] &&
		   pbd->lambda_history[0] && pbd->lambda_history[1];
}
static sere_status build_layout( sere_pbd* pbd, const int32_t* a, const int32_t* b )
{
	const int32_t n = pbd->particle_count, count = pbd->constraint_count, colors = pbd->colors;
	int32_t* band_of_slot = malloc( sizeof( int32_t ) * (size_t) n );
	int32_t* ends = calloc( (size_t) n + 1, sizeof( int32_t ) );
	sere_sort_item* keys = malloc( sizeof( sere_sort_item ) * (size_t) count );
	pbd->band_start = sere_alloc( sizeof( int32_t ) * ( MAX_BANDS + 1 ) );
	if ( band_of_slot == NULL || ends == NULL || keys == NULL || pbd->band_start == NULL )
	{
		free( band_of_slot ), free( ends ), free( keys );
		return SERE_ERR_MEMORY;
	}
	for ( int32_t k = 0; k < count; ++k )
	{
		ends[pbd->slot[a[k]] + 1] += 1;
		ends[pbd->slot[b[k]] + 1] += 1;
	}
	for ( int32_t s = 0; s < n; ++s )
	{
		ends[s + 1] += ends[s];
	}
	/* The band count depends on the mesh only (never on threads): determinism. One band
	 * always passes (its only bounds are 0 and n). */
	int32_t bands = n / BAND_PARTICLES;
	bands = bands < 1 ? 1 : bands > MAX_BANDS ? MAX_BANDS : bands;
	while ( !assign_bands( bands, n, ends, a, b, count, pbd->slot, pbd->band_start, band_of_slot ) )
	{
		bands -= 1;
	}
	free( ends );
	pbd->bands = bands;
	pbd->items = 2 * bands - 1;
	const int32_t segments = pbd->items * colors;
	pbd->segment = sere_alloc( sizeof( int32_t ) * ( (size_t) segments + 1 ) );
	int32_t* fill = calloc( (size_t) segments + 1, sizeof( int32_t ) );
	if ( pbd->segment == NULL || fill == NULL )
	{
		free( band_of_slot ), free( keys ), free( fill );
		return SERE_ERR_MEMORY;
	}
	pbd->interface_count = 0;
	for ( int32_t k = 0; k < count; ++k )
	{
		int32_t sa = pbd->slot[a[k]], sb = pbd->slot[b[k]];
		int32_t ra = band_of_slot[sa], rb = band_of_slot[sb];
		int32_t item = ra == rb ? ra : bands + ( ra < rb ? ra : rb );
		pbd->interface_count += ra != rb;
		int64_t seg = (int64_t) item * colors + pbd->coloring.color[k];
		/* segment, then the lower slot of the two ends */
		keys[k] = ( sere_sort_item ){ (uint64_t) ( seg << 32 | (int64_t) ( sa < sb ? sa : sb ) ), k, 0 };
		fill[seg] += 1;
	}
	for ( int32_t g = 0; g < segments; ++g )
	{
		pbd->segment[g + 1] = pbd->segment[g] + ( ( fill[g] + LANES - 1 ) / LANES ) * LANES;
	}
	pbd->lanes = pbd->segment[segments];
	if ( !alloc_lanes( pbd, n ) )
	{
		free( band_of_slot ), free( keys ), free( fill );
		return SERE_ERR_MEMORY;
	}
	/* Within a segment, constraints by their lower slot: neighbors in space share SIMD steps
	 * and cache lines. */
	sere_sort_items( keys, count );
	for ( int32_t g = 0; g < segments; ++g )
	{
		fill[g] = pbd->segment[g];
	}
	for ( int32_t j = 0; j < count; ++j )
	{
		int32_t k = keys[j].index;
		int32_t q = fill[keys[j].key >> 32]++;
		pbd->ia[q] = 4 * pbd->slot[a[k]];
		pbd->ib[q] = 4 * pbd->slot[b[k]];
		pbd->source[q] = k;
	}
	/* Padding lanes join the item's own dummy pair, unit length apart with w = 0: they measure
	 * C = 0, move nothing, and no two threads ever write the same dummy. */
	const int32_t dummies = ( n + 3 ) & ~3;
	for ( int32_t g = 0; g < segments; ++g )
	{
		int32_t item = g / colors;
		for ( int32_t q = fill[g]; q < pbd->segment[g + 1]; ++q )
		{
			pbd->ia[q] = 4 * ( dummies + 4 * item );
			pbd->ib[q] = 4 * ( dummies + 4 * item + 1 );
			pbd->source[q] = -1;
			pbd->rest[q] = 1.0f;
		}
	}
	for ( int32_t q = 0; q < pbd->lanes; ++q )
	{
		pbd->weight[q] = 1.0f;
	}
	for ( int32_t item = 0; item < pbd->items; ++item )
	{
		pbd->packed[0][4 * ( dummies + 4 * item + 1 )] = 1.0f;
		pbd->packed[1][4 * ( dummies + 4 * item + 1 )] = 1.0f;
	}
	free( band_of_slot ), free( keys ), free( fill );
	return SERE_OK;
}

/* Particle → constraint lists for the Jacobi gather, in lane order. */
static sere_status build_adjacency( sere_pbd* pbd )
{
	const int32_t n = pbd->particle_count;
	pbd->adjacency_offset = sere_alloc( sizeof( int32_t ) * ( (size_t) n + 1 ) );
	pbd->adjacency = sere_alloc( sizeof( int32_t ) * 4 * (size_t) pbd->constraint_count );
	pbd->inv_degree = sere_alloc( sizeof( float ) * (size_t) n );
	int32_t* fill = malloc( sizeof( int32_t ) * (size_t) n );
	if ( !pbd->adjacency_offset || !pbd->adjacency || !pbd->inv_degree || !fill )
	{
		free( fill );
		return SERE_ERR_MEMORY;
	}
	for ( int32_t q = 0; q < pbd->lanes; ++q )
	{
		if ( pbd->source[q] >= 0 )
		{
			pbd->adjacency_offset[pbd->ia[q] / 4 + 1] += 1;
			pbd->adjacency_offset[pbd->ib[q] / 4 + 1] += 1;
		}
	}
	for ( int32_t s = 0; s < n; ++s )
	{
		int32_t degree = pbd->adjacency_offset[s + 1];
		pbd->inv_degree[s] = degree > 0 ? 1.0f / (float) degree : 0.0f;
		pbd->adjacency_offset[s + 1] += pbd->adjacency_offset[s];
	}
	memcpy( fill, pbd->adjacency_offset, sizeof( int32_t ) * (size_t) n );
	for ( int32_t q = 0; q < pbd->lanes; ++q )
	{
		if ( pbd->source[q] >= 0 )
		{
			int32_t ea = 2 * fill[pbd->ia[q] / 4]++, eb = 2 * fill[pbd->ib[q] / 4]++;
			pbd->adjacency[ea] = q, pbd->adjacency[ea + 1] = pbd->ib[q];
			pbd->adjacency[eb] = q, pbd->adjacency[eb + 1] = pbd->ia[q];
		}
	}
	free( fill );
	return SERE_OK;
}

sere_status sere_pbd_create( const int32_t* a, const int32_t* b, int32_t count, int32_t particle_count, sere_pbd** out )
{
	if ( out == NULL )
	{
		return SERE_ERR_ARGUMENT;
	}
	*out = NULL;
	sere_pbd* pbd = sere_alloc( sizeof( *pbd ) );
	if ( pbd == NULL )
	{
		return SERE_ERR_MEMORY;
	}
	sere_status status = sere_coloring_create( a, b, count, particle_count, &pbd->coloring );
	if ( status != SERE_OK )
	{
		sere_free( pbd );
		return status;
	}
	pbd->particle_count = particle_count;
	pbd->constraint_count = count;
	pbd->colors = pbd->coloring.color_count;
	pbd->one = 1.0f;
	pbd->slot = sere_alloc( sizeof( int32_t ) * (size_t) particle_count );
	pbd->threads = sere_alloc( sizeof( thread_slot ) * MAX_THREADS );
	pbd->counters = sere_alloc( sizeof( padded_counter ) * 2 * MAX_THREADS );
	pbd->done = sere_alloc( sizeof( padded_counter ) * ( 2 * MAX_BANDS - 1 ) );
	pbd->barrier = sere_alloc( sizeof( sere_spin_barrier ) );
	pbd->particle = sere_alloc( sizeof( int32_t ) * (size_t) particle_count );
	if ( !pbd->slot || !pbd->particle || !pbd->threads || !pbd->counters || !pbd->done || !pbd->barrier )
	{
		sere_pbd_destroy( pbd );
		return SERE_ERR_MEMORY;
	}
	atomic_init( &pbd->barrier->arrived, 0u );
	atomic_init( &pbd->barrier->generation, 0u );
	for ( int32_t c = 0; c < 2 * MAX_THREADS; ++c )
	{
		atomic_init( &pbd->counters[c].value, 0 );
	}
	for ( int32_t item = 0; item < 2 * MAX_BANDS - 1; ++item )
	{
		atomic_init( &pbd->done[item].value, 0 );
	}
	status = order_particles( a, b, count, particle_count, pbd->particle );
	for ( int32_t s = 0; status == SERE_OK && s < particle_count; ++s )
	{
		pbd->slot[pbd->particle[s]] = s;
	}
	if ( status == SERE_OK )
	{
		status = build_layout( pbd, a, b );
	}
	if ( status == SERE_OK )
	{
		status = build_adjacency( pbd );
	}
	if ( status != SERE_OK )
	{
		sere_pbd_destroy( pbd );
		return status;
	}
	*out = pbd;
	return SERE_OK;
}

sere_status sere_pbd_set_rest( sere_pbd* pbd, const float* rest )
{
	if ( pbd == NULL || rest == NULL )
	{
		return SERE_ERR_ARGUMENT;
	}
	int bad = 0;
	const int32_t lanes = pbd->lanes;
	const int32_t* source = pbd->source;
	float* lane_rest = pbd->rest;
#pragma omp parallel for num_threads( sere_team_for( pbd->thread_count ) ) schedule( static ) reduction( | : bad )
	for ( int32_t q = 0; q < lanes; ++q )
	{
		if ( source[q] >= 0 )
		{
			float l = rest[source[q]];
			bad |= !( l > 0.0f && l <= FLT_MAX );
			lane_rest[q] = l;
		}
	}
	pbd->rest_valid = !bad;
	return bad ? SERE_ERR_GEOMETRY : SERE_OK;
}

sere_status sere_pbd_ground_push( const sere_pbd* pbd, float* push )
{
	if ( pbd == NULL || push == NULL )
	{
		return SERE_ERR_ARGUMENT;
	}
	const int32_t n = pbd->particle_count;
	const int32_t threads = sere_team_for( pbd->thread_count );
#pragma omp parallel for num_threads( threads ) schedule( static )
	for ( int32_t i = 0; i < n; ++i )
	{
		push[i] += pbd->push[pbd->slot[i]];
	}
	return SERE_OK;
}

sere_status sere_pbd_set_compliance_weights( sere_pbd* pbd, const float* weight )
{
	if ( pbd == NULL )
	{
		return SERE_ERR_ARGUMENT;
	}
	if ( weight != NULL )
	{
		for ( int32_t k = 0; k < pbd->constraint_count; ++k )
		{
			if ( !( weight[k] >= 0.0f && weight[k] <= FLT_MAX ) )
			{
				return SERE_ERR_ARGUMENT;
			}
		}
	}
	for ( int32_t q = 0; q < pbd->lanes; ++q )
	{
		pbd->weight[q] = weight != NULL && pbd->source[q] >= 0 ? weight[pbd->source[q]] : 1.0f;
	}
	return SERE_OK;
}

sere_status sere_pbd_set_threads( sere_pbd* pbd, int32_t threads )
{
	return pbd == NULL ? SERE_ERR_ARGUMENT : sere_threads_store( &pbd->thread_count, threads );
}

void sere_pbd_predict( int32_t count, const float* x, const float* y, const float* z, float* vx, float* vy, float* vz,
					   float* px, float* py, float* pz, const float* inv_m, const float gravity[3], float dt,
					   int32_t threads )
{
	const float gx = gravity[0] * dt, gy = gravity[1] * dt, gz = gravity[2] * dt;
#pragma omp parallel for simd num_threads( sere_team_for( threads ) ) schedule( static )
	for ( int32_t i = 0; i < count; ++i )
	{
		float free_particle = inv_m[i] > 0.0f ? 1.0f : 0.0f;
		vx[i] = free_particle * ( vx[i] + gx );
		vy[i] = free_particle * ( vy[i] + gy );
		vz[i] = free_particle * ( vz[i] + gz );
		px[i] = x[i] + vx[i] * dt;
		py[i] = y[i] + vy[i] * dt;
		pz[i] = z[i] + vz[i] * dt;
	}
}

void sere_pbd_finish( int32_t count, float* x, float* y, float* z, float* vx, float* vy, float* vz, const float* px,
					  const float* py, const float* pz, float dt, int32_t threads )
{
	const float inv_dt = 1.0f / dt;
#pragma omp parallel for simd num_threads( sere_team_for( threads ) ) schedule( static )
	for ( int32_t i = 0; i < count; ++i )
	{
		vx[i] = ( px[i] - x[i] ) * inv_dt;
		vy[i] = ( py[i] - y[i] ) * inv_dt;
		vz[i] = ( pz[i] - z[i] ) * inv_dt;
		x[i] = px[i];
		y[i] = py[i];
		z[i] = pz[i];
	}
}
