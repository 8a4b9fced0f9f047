/* nanosleep, for the barrier's back-off when a thread has lost its core; sched_getaffinity
 * for internal/team.h. */
#define _GNU_SOURCE

#include "solve/pbd.h"
#include "core/internal/team.h"

#include <float.h>
#include <math.h>
#include <omp.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#if defined( __AVX512F__ ) || defined( __AVX__ )
#include <immintrin.h>
#endif

/* For the block functions: each pass mode gets its own copy of the block loop (project_colors),
 * and GCC's size limits would otherwise leave the block an out-of-line call with its operands
 * in memory. */
#define FORCE_INLINE static inline __attribute__( ( always_inline ) )

enum
{
	/* Constraints per block: one 512-bit register of floats (two 256-bit halves with AVX). */
	LANES = 16,
	/* Bands hold at least this many particles, so the constraints joining two bands stay a
	 * small share (on the maple, 8 bands: 6% of the constraints). */
	BAND_PARTICLES = 1600,
	MAX_BANDS = 8,
	/* Threads past this many are not started (per-thread slots live in the workspace). */
	MAX_THREADS = 64,
	/* A waiting thread naps this long at a time once it has spun SPIN_SECONDS. */
	NAP_NANOSECONDS = 50000,
};

#define SPIN_SECONDS 100e-6

/* What one pass over a constraint block does. */
typedef enum block_mode
{
	MODE_GAUSS_SEIDEL, /* project and write both ends */
	MODE_JACOBI,	   /* measure and store the correction per constraint */
	MODE_MEASURE,	   /* measure only */
	MODE_TOUCH,		   /* load and store both ends unchanged (the memory floor) */
} block_mode;

/* What a pass claims items from: a sweep's work lists (bands, then the cuts between them) or
 * every item (the read-only and Jacobi passes). */
typedef enum pass_kind
{
	PASS_SWEEP,
	PASS_ALL,
} pass_kind;

enum
{
	FLAG_ZERO_LENGTH = 1,
	FLAG_NONFINITE = 2,
	FLAG_NEGATIVE_MASS = 4,
};

/* Per-thread results of a pass, double-buffered by pass parity so a fast thread can publish
 * the next pass's values while a slow one still reads this one's. One cache line each. */
typedef struct thread_slot
{
	_Alignas( 64 ) float worst[2];
	int32_t flags[2];
} thread_slot;

/* A counter alone on its cache line. */
typedef struct padded_counter
{
	_Alignas( 64 ) atomic_int value;
} padded_counter;

/* A sense-free spin barrier. libgomp's barrier makes a futex system call at every release,
 * about 1 µs on this machine's virtual CPUs even for one thread; a sweep crosses several per
 * iteration, so the projection synchronizes with this one instead (0.2–0.5 µs for two threads,
 * nothing for one). */
typedef struct spin_barrier
{
	_Alignas( 64 ) atomic_uint arrived;
	_Alignas( 64 ) atomic_uint generation;
} spin_barrier;

struct sere_pbd
{
	int32_t particle_count, constraint_count;
	sere_coloring coloring;
	int32_t colors;
	int32_t bands, items; /* items: bands 0..R−1, then cut r (bands r, r+1) is item R + r */
	int32_t interface_count;
	int32_t* segment;		   /* items·colors + 1 lane offsets, multiples of LANES: item w, color c */
	int32_t lanes;			   /* segment[items·colors] */
	int32_t *ia, *ib;		   /* per lane: float offset 4·slot of each end */
	int32_t* source;		   /* per lane: the caller's constraint index, −1 for padding */
	float* rest;			   /* per lane; padding lanes keep 1 */
	float* lambda;			   /* per lane, XPBD multipliers */
	float* weight;			   /* per lane, XPBD compliance weight (α_j = α · weight_j); padding keeps 1 */
	float* factor;			   /* per lane, Jacobi: the f of the block below */
	int32_t* slot;			   /* particle → slot (its place in breadth-first order) */
	int32_t* particle;		   /* slot → particle, for slots < particle_count */
	int32_t* band_start;	   /* bands + 1 slot offsets, multiples of 4 but the last (particle_count) */
	int32_t slot_count;		   /* particles rounded up to 4, then a dummy pair per item */
	float* packed[2];		   /* (x, y, z, w) per slot; Jacobi alternates the two, the others use [0] */
	float* history[2];		   /* Chebyshev: records of the last two iterates, x_{k−1} and x_k */
	float* lambda_history[2];  /* Chebyshev: multipliers of the last two iterates, per lane */
	int32_t* adjacency_offset; /* per slot < particle_count, Jacobi */
	int32_t* adjacency;		   /* pairs (lane, 4·slot of the other end) */
	float* inv_degree;		   /* per slot: 1/n_i, 0 for a particle without constraints */
	float one;				   /* 1.0f, opaque to the compiler so sere_pbd_touch keeps its stores */
	int rest_valid;
	thread_slot* threads;	  /* MAX_THREADS */
	padded_counter* counters; /* 2 × MAX_THREADS: next item of each thread's list, by pass parity */
	padded_counter* done;	  /* per item: the sweep of the current call that last projected it */
	spin_barrier* barrier;
};

sere_pbd_params sere_pbd_params_default( void )
{
	sere_pbd_params params = {
		.stiffness = 1.0f,
		.tolerance = 1e-3f,
		.max_iterations = 200,
		.compliance = 0.0f,
		.dt = 0.002f,
		.relaxation = 1.5f,
		.linear_stiffness = 0,
		.warm = 0,
		.chebyshev_rho = 0.0f,
		.chebyshev_delay = 10,
		.stall = 0.0f,
	};
	return params;
}

sere_status sere_pbd_project_stalling( sere_pbd* pbd, float* px, float* py, float* pz, const float* inv_m,
									   const sere_pbd_params* params, sere_pbd_report* report, int* stalled )
{
	*stalled = 0;
	if ( params->stall <= 0.0f || params->linear_stiffness )
	{
		return sere_pbd_project( pbd, px, py, pz, inv_m, params, report );
	}
	sere_pbd_params window = *params;
	int32_t done = 0;
	float previous = INFINITY;
	while ( done < params->max_iterations )
	{
		int32_t left = params->max_iterations - done;
		window.max_iterations = left < SERE_PBD_STALL_WINDOW ? left : SERE_PBD_STALL_WINDOW;
		sere_status status = sere_pbd_project( pbd, px, py, pz, inv_m, &window, report );
		if ( status != SERE_OK )
		{
			return status;
		}
		done += report->iterations;
		if ( !report->hit_cap )
		{
			break;
		}
		if ( report->max_strain > ( 1.0f - params->stall ) * previous )
		{
			*stalled = done < params->max_iterations;
			break;
		}
		previous = report->max_strain;
	}
	report->iterations = done;
	report->hit_cap = report->hit_cap && !*stalled;
	return SERE_OK;
}

void sere_pbd_destroy( sere_pbd* pbd )
{
	if ( pbd == NULL )
	{
		return;
	}
	sere_coloring_destroy( &pbd->coloring );
	sere_free( pbd->segment );
	sere_free( pbd->ia );
	sere_free( pbd->ib );
	sere_free( pbd->source );
	sere_free( pbd->rest );
	sere_free( pbd->lambda );
	sere_free( pbd->weight );
	sere_free( pbd->factor );
	sere_free( pbd->slot );
	sere_free( pbd->particle );
	sere_free( pbd->band_start );
	sere_free( pbd->packed[0] );
	sere_free( pbd->packed[1] );
	sere_free( pbd->history[0] );
	sere_free( pbd->history[1] );
	sere_free( pbd->lambda_history[0] );
	sere_free( pbd->lambda_history[1] );
	sere_free( pbd->adjacency_offset );
	sere_free( pbd->adjacency );
	sere_free( pbd->inv_degree );
	sere_free( pbd->threads );
	sere_free( pbd->counters );
	sere_free( pbd->done );
	sere_free( pbd->barrier );
	sere_free( pbd );
}

const sere_coloring* sere_pbd_coloring( const sere_pbd* pbd )
{
	return &pbd->coloring;
}

sere_pbd_info sere_pbd_get_info( const sere_pbd* pbd )
{
	sere_pbd_info info = {
		.colors = pbd->coloring.color_count,
		.min_batch = pbd->coloring.min_batch,
		.max_batch = pbd->coloring.max_batch,
		.bands = pbd->bands,
		.interface_constraints = pbd->interface_count,
		.lanes = pbd->lanes,
	};
	return info;
}

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

typedef struct lane_key
{
	int64_t key; /* segment, then lower slot of the two ends */
	int32_t constraint;
} lane_key;

static int compare_lane_keys( const void* p, const void* q )
{
	const lane_key* u = p;
	const lane_key* v = q;
	if ( u->key != v->key )
	{
		return u->key < v->key ? -1 : 1;
	}
	return ( u->constraint > v->constraint ) - ( u->constraint < v->constraint );
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

static sere_status build_layout( sere_pbd* pbd, const int32_t* a, const int32_t* b )
{
	const int32_t n = pbd->particle_count, count = pbd->constraint_count, colors = pbd->colors;
	int32_t* band_of_slot = malloc( sizeof( int32_t ) * (size_t) n );
	int32_t* ends = calloc( (size_t) n + 1, sizeof( int32_t ) );
	lane_key* keys = malloc( sizeof( lane_key ) * (size_t) count );
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
		keys[k].key = seg << 32 | (int64_t) ( sa < sb ? sa : sb );
		keys[k].constraint = k;
		fill[seg] += 1;
	}
	for ( int32_t g = 0; g < segments; ++g )
	{
		pbd->segment[g + 1] = pbd->segment[g] + ( ( fill[g] + LANES - 1 ) / LANES ) * LANES;
	}
	pbd->lanes = pbd->segment[segments];
	const size_t lanes = (size_t) pbd->lanes;
	pbd->ia = sere_alloc( sizeof( int32_t ) * lanes );
	pbd->ib = sere_alloc( sizeof( int32_t ) * lanes );
	pbd->source = sere_alloc( sizeof( int32_t ) * lanes );
	pbd->rest = sere_alloc( sizeof( float ) * lanes );
	pbd->lambda = sere_alloc( sizeof( float ) * lanes );
	pbd->weight = sere_alloc( sizeof( float ) * lanes );
	pbd->factor = sere_alloc( sizeof( float ) * lanes );
	pbd->slot_count = ( ( n + 3 ) & ~3 ) + 4 * pbd->items;
	pbd->packed[0] = sere_alloc( sizeof( float ) * 4 * (size_t) pbd->slot_count );
	pbd->packed[1] = sere_alloc( sizeof( float ) * 4 * (size_t) pbd->slot_count );
	for ( int h = 0; h < 2; ++h )
	{
		pbd->history[h] = sere_alloc( sizeof( float ) * 4 * (size_t) pbd->slot_count );
		pbd->lambda_history[h] = sere_alloc( sizeof( float ) * lanes );
	}
	if ( !pbd->ia || !pbd->ib || !pbd->source || !pbd->rest || !pbd->lambda || !pbd->weight || !pbd->factor ||
		 !pbd->packed[0] || !pbd->packed[1] || !pbd->history[0] || !pbd->history[1] || !pbd->lambda_history[0] ||
		 !pbd->lambda_history[1] )
	{
		free( band_of_slot ), free( keys ), free( fill );
		return SERE_ERR_MEMORY;
	}
	/* Within a segment, constraints by their lower slot: neighbors in space share SIMD steps
	 * and cache lines. */
	qsort( keys, (size_t) count, sizeof( lane_key ), compare_lane_keys );
	for ( int32_t g = 0; g < segments; ++g )
	{
		fill[g] = pbd->segment[g];
	}
	for ( int32_t j = 0; j < count; ++j )
	{
		int32_t k = keys[j].constraint;
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
	sere_status status = sere_color_springs( a, b, count, particle_count, &pbd->coloring );
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
	pbd->barrier = sere_alloc( sizeof( spin_barrier ) );
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
#pragma omp parallel for num_threads( sere_team_default() ) schedule( static ) reduction( | : bad )
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

void sere_pbd_predict( int32_t count, const float* x, const float* y, const float* z, float* vx, float* vy, float* vz,
					   float* px, float* py, float* pz, const float* inv_m, const float gravity[3], float dt )
{
	const float gx = gravity[0] * dt, gy = gravity[1] * dt, gz = gravity[2] * dt;
#pragma omp parallel for simd num_threads( sere_team_default() ) schedule( static )
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
					  const float* py, const float* pz, float dt )
{
	const float inv_dt = 1.0f / dt;
#pragma omp parallel for simd num_threads( sere_team_default() ) schedule( static )
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

/* ---------------------------------------------------------------------------------------
 * The constraint block: 16 constraints of one color, no particle twice.
 *
 * Per lane, in this order (the scalar build does the same operations, so both round alike):
 *   d = p_b − p_a, len = √((dx² + dy²) + dz²), C = len − l                    (Jeong Eq. 13)
 *   residual r = C (PBD) or C + α̃λ (XPBD); strain |r|/l
 *   PBD:  f = (k C)/((w_a + w_b) len), 0 when w_a + w_b = 0
 *   XPBD: Δλ = (−C − α̃λ)/(w_a + w_b + α̃), λ += Δλ, f = −Δλ/len
 *   p_a += (w_a f) d, p_b −= (w_b f) d       (Jacobi: store f instead) */

typedef struct block_context
{
	float* packed;
	const int32_t* ia;
	const int32_t* ib;
	const float* rest;
	float* lambda;
	const float* weight;
	float* factor;
	float k, alpha, one;
} block_context;

#if defined( __AVX512F__ )

typedef struct lane_accum
{
	__m512 worst;
	__mmask16 zero, nonfinite;
} lane_accum;

FORCE_INLINE lane_accum lane_accum_start( void )
{
	lane_accum acc = { _mm512_setzero_ps(), 0, 0 };
	return acc;
}

FORCE_INLINE void lane_accum_finish( const lane_accum* acc, float* worst, int32_t* flags )
{
	float w = _mm512_reduce_max_ps( acc->worst );
	*worst = w > *worst ? w : *worst;
	*flags |= ( acc->zero ? FLAG_ZERO_LENGTH : 0 ) | ( acc->nonfinite ? FLAG_NONFINITE : 0 );
}

/* Four (x, y, z, w) records into one register per component: record 4j + r sits in 128-bit
 * lane j of register r, then a 4×4 transpose inside each 128-bit lane. This replaces AVX-512
 * gathers and scatters, which on this machine cost 3× as much for the same sweep. */
FORCE_INLINE void load_records( const float* packed, const int32_t* at, __m512* x, __m512* y, __m512* z, __m512* w )
{
	__m512 r0 = _mm512_castps128_ps512( _mm_load_ps( packed + at[0] ) );
	__m512 r1 = _mm512_castps128_ps512( _mm_load_ps( packed + at[1] ) );
	__m512 r2 = _mm512_castps128_ps512( _mm_load_ps( packed + at[2] ) );
	__m512 r3 = _mm512_castps128_ps512( _mm_load_ps( packed + at[3] ) );
	r0 = _mm512_insertf32x4( r0, _mm_load_ps( packed + at[4] ), 1 );
	r1 = _mm512_insertf32x4( r1, _mm_load_ps( packed + at[5] ), 1 );
	r2 = _mm512_insertf32x4( r2, _mm_load_ps( packed + at[6] ), 1 );
	r3 = _mm512_insertf32x4( r3, _mm_load_ps( packed + at[7] ), 1 );
	r0 = _mm512_insertf32x4( r0, _mm_load_ps( packed + at[8] ), 2 );
	r1 = _mm512_insertf32x4( r1, _mm_load_ps( packed + at[9] ), 2 );
	r2 = _mm512_insertf32x4( r2, _mm_load_ps( packed + at[10] ), 2 );
	r3 = _mm512_insertf32x4( r3, _mm_load_ps( packed + at[11] ), 2 );
	r0 = _mm512_insertf32x4( r0, _mm_load_ps( packed + at[12] ), 3 );
	r1 = _mm512_insertf32x4( r1, _mm_load_ps( packed + at[13] ), 3 );
	r2 = _mm512_insertf32x4( r2, _mm_load_ps( packed + at[14] ), 3 );
	r3 = _mm512_insertf32x4( r3, _mm_load_ps( packed + at[15] ), 3 );
	__m512d t0 = _mm512_castps_pd( _mm512_unpacklo_ps( r0, r1 ) ); /* x0 x1 y0 y1 per lane */
	__m512d t1 = _mm512_castps_pd( _mm512_unpackhi_ps( r0, r1 ) ); /* z0 z1 w0 w1 */
	__m512d t2 = _mm512_castps_pd( _mm512_unpacklo_ps( r2, r3 ) );
	__m512d t3 = _mm512_castps_pd( _mm512_unpackhi_ps( r2, r3 ) );
	*x = _mm512_castpd_ps( _mm512_unpacklo_pd( t0, t2 ) );
	*y = _mm512_castpd_ps( _mm512_unpackhi_pd( t0, t2 ) );
	*z = _mm512_castpd_ps( _mm512_unpacklo_pd( t1, t3 ) );
	*w = _mm512_castpd_ps( _mm512_unpackhi_pd( t1, t3 ) );
}

/* The inverse of load_records: four components into records, 16 stores of 128 bits. */
FORCE_INLINE void store_records( float* packed, const int32_t* at, __m512 x, __m512 y, __m512 z, __m512 w )
{
	__m512d t0 = _mm512_castps_pd( _mm512_unpacklo_ps( x, y ) );
	__m512d t1 = _mm512_castps_pd( _mm512_unpackhi_ps( x, y ) );
	__m512d t2 = _mm512_castps_pd( _mm512_unpacklo_ps( z, w ) );
	__m512d t3 = _mm512_castps_pd( _mm512_unpackhi_ps( z, w ) );
	__m512 r0 = _mm512_castpd_ps( _mm512_unpacklo_pd( t0, t2 ) );
	__m512 r1 = _mm512_castpd_ps( _mm512_unpackhi_pd( t0, t2 ) );
	__m512 r2 = _mm512_castpd_ps( _mm512_unpacklo_pd( t1, t3 ) );
	__m512 r3 = _mm512_castpd_ps( _mm512_unpackhi_pd( t1, t3 ) );
	_mm_store_ps( packed + at[0], _mm512_castps512_ps128( r0 ) );
	_mm_store_ps( packed + at[1], _mm512_castps512_ps128( r1 ) );
	_mm_store_ps( packed + at[2], _mm512_castps512_ps128( r2 ) );
	_mm_store_ps( packed + at[3], _mm512_castps512_ps128( r3 ) );
	_mm_store_ps( packed + at[4], _mm512_extractf32x4_ps( r0, 1 ) );
	_mm_store_ps( packed + at[5], _mm512_extractf32x4_ps( r1, 1 ) );
	_mm_store_ps( packed + at[6], _mm512_extractf32x4_ps( r2, 1 ) );
	_mm_store_ps( packed + at[7], _mm512_extractf32x4_ps( r3, 1 ) );
	_mm_store_ps( packed + at[8], _mm512_extractf32x4_ps( r0, 2 ) );
	_mm_store_ps( packed + at[9], _mm512_extractf32x4_ps( r1, 2 ) );
	_mm_store_ps( packed + at[10], _mm512_extractf32x4_ps( r2, 2 ) );
	_mm_store_ps( packed + at[11], _mm512_extractf32x4_ps( r3, 2 ) );
	_mm_store_ps( packed + at[12], _mm512_extractf32x4_ps( r0, 3 ) );
	_mm_store_ps( packed + at[13], _mm512_extractf32x4_ps( r1, 3 ) );
	_mm_store_ps( packed + at[14], _mm512_extractf32x4_ps( r2, 3 ) );
	_mm_store_ps( packed + at[15], _mm512_extractf32x4_ps( r3, 3 ) );
}

/* What the measuring part of a block leaves for the moving part: both ends and the factor f. */
typedef struct part_state
{
	__m512 ax, ay, az, aw, bx, by, bz, bw, f;
} part_state;

/* Loads both ends of the block at q and measures it (Jeong Eq. 13): the residual into acc and, unless
 * mode is MODE_MEASURE, the factor f (XPBD: and the multiplier λ; Jacobi: f stored per lane). */
FORCE_INLINE part_state measure_part( const block_context* ctx, int32_t q, block_mode mode, int xpbd, lane_accum* acc )
{
	part_state h;
	load_records( ctx->packed, ctx->ia + q, &h.ax, &h.ay, &h.az, &h.aw );
	load_records( ctx->packed, ctx->ib + q, &h.bx, &h.by, &h.bz, &h.bw );
	const __m512 zero = _mm512_setzero_ps();
	__m512 dx = _mm512_sub_ps( h.bx, h.ax ), dy = _mm512_sub_ps( h.by, h.ay ), dz = _mm512_sub_ps( h.bz, h.az );
	__m512 len2 =
		_mm512_add_ps( _mm512_add_ps( _mm512_mul_ps( dx, dx ), _mm512_mul_ps( dy, dy ) ), _mm512_mul_ps( dz, dz ) );
	__m512 len = _mm512_sqrt_ps( len2 );
	__m512 rest = _mm512_load_ps( ctx->rest + q );
	__m512 c = _mm512_sub_ps( len, rest ); /* Jeong Eq. 13 */
	acc->zero |= _mm512_cmp_ps_mask( len, zero, _CMP_EQ_OQ );
	acc->nonfinite |= _mm512_cmp_ps_mask( len, _mm512_set1_ps( FLT_MAX ), _CMP_NLE_UQ );
	__m512 wsum = _mm512_add_ps( h.aw, h.bw );
	__m512 lambda = zero, alpha = zero, residual = c;
	if ( xpbd )
	{
		alpha = _mm512_mul_ps( _mm512_set1_ps( ctx->alpha ), _mm512_load_ps( ctx->weight + q ) );
		lambda = _mm512_load_ps( ctx->lambda + q );
		residual = _mm512_add_ps( c, _mm512_mul_ps( alpha, lambda ) );
	}
	acc->worst = _mm512_max_ps( acc->worst, _mm512_div_ps( _mm512_abs_ps( residual ), rest ) );
	h.f = zero;
	if ( mode == MODE_MEASURE )
	{
		return h;
	}
	if ( xpbd )
	{
		__m512 denominator = _mm512_add_ps( wsum, alpha );
		__mmask16 movable = _mm512_cmp_ps_mask( denominator, zero, _CMP_GT_OQ );
		__m512 numerator = _mm512_sub_ps( _mm512_sub_ps( zero, c ), _mm512_mul_ps( alpha, lambda ) );
		__m512 dlambda = _mm512_maskz_div_ps( movable, numerator, denominator );
		_mm512_store_ps( ctx->lambda + q, _mm512_add_ps( lambda, dlambda ) );
		h.f = _mm512_div_ps( _mm512_sub_ps( zero, dlambda ), len );
	}
	else
	{
		__mmask16 movable = _mm512_cmp_ps_mask( wsum, zero, _CMP_GT_OQ );
		h.f = _mm512_maskz_div_ps( movable, _mm512_mul_ps( _mm512_set1_ps( ctx->k ), c ), _mm512_mul_ps( wsum, len ) );
	}
	if ( mode == MODE_JACOBI )
	{
		_mm512_store_ps( ctx->factor + q, h.f );
	}
	return h;
}

/* The moving part of a Gauss–Seidel block: p_a += (w_a f) d, p_b −= (w_b f) d (Jeong Eq. 13), stored.
 * d = p_b − p_a again, the same operation on the same values as in measure_part, so the same
 * bits; recomputing it keeps three registers fewer alive between the two parts. */
FORCE_INLINE void move_part( const block_context* ctx, int32_t q, const part_state* h )
{
	__m512 dx = _mm512_sub_ps( h->bx, h->ax ), dy = _mm512_sub_ps( h->by, h->ay ), dz = _mm512_sub_ps( h->bz, h->az );
	__m512 fa = _mm512_mul_ps( h->aw, h->f ), fb = _mm512_mul_ps( h->bw, h->f );
	store_records( ctx->packed, ctx->ia + q, _mm512_add_ps( h->ax, _mm512_mul_ps( fa, dx ) ),
				   _mm512_add_ps( h->ay, _mm512_mul_ps( fa, dy ) ), _mm512_add_ps( h->az, _mm512_mul_ps( fa, dz ) ),
				   h->aw );
	store_records( ctx->packed, ctx->ib + q, _mm512_sub_ps( h->bx, _mm512_mul_ps( fb, dx ) ),
				   _mm512_sub_ps( h->by, _mm512_mul_ps( fb, dy ) ), _mm512_sub_ps( h->bz, _mm512_mul_ps( fb, dz ) ),
				   h->bw );
}

FORCE_INLINE void touch_part( const block_context* ctx, int32_t q )
{
	__m512 ax, ay, az, aw, bx, by, bz, bw;
	load_records( ctx->packed, ctx->ia + q, &ax, &ay, &az, &aw );
	load_records( ctx->packed, ctx->ib + q, &bx, &by, &bz, &bw );
	const __m512 one = _mm512_set1_ps( ctx->one );
	store_records( ctx->packed, ctx->ia + q, _mm512_mul_ps( ax, one ), _mm512_mul_ps( ay, one ),
				   _mm512_mul_ps( az, one ), aw );
	store_records( ctx->packed, ctx->ib + q, _mm512_mul_ps( bx, one ), _mm512_mul_ps( by, one ),
				   _mm512_mul_ps( bz, one ), bw );
}

/* Constraints per measure/move part: one block of 16. */
#define PART LANES

#elif defined( __AVX__ )

/* AVX (256-bit) build: each block of LANES constraints as two halves of eight. Lanes of a
 * block share no particle, so the halves are independent and the result has the bits of the
 * AVX-512 and portable builds. Without it a machine lacking AVX-512 ran the one-lane portable
 * loop, 7-10x slower per sweep. */
typedef struct lane_accum
{
	__m256 worst;
	int zero, nonfinite;
} lane_accum;

FORCE_INLINE lane_accum lane_accum_start( void )
{
	lane_accum acc = { _mm256_setzero_ps(), 0, 0 };
	return acc;
}

FORCE_INLINE void lane_accum_finish( const lane_accum* acc, float* worst, int32_t* flags )
{
	__m128 m = _mm_max_ps( _mm256_castps256_ps128( acc->worst ), _mm256_extractf128_ps( acc->worst, 1 ) );
	m = _mm_max_ps( m, _mm_movehl_ps( m, m ) );
	m = _mm_max_ss( m, _mm_shuffle_ps( m, m, 1 ) );
	float w = _mm_cvtss_f32( m );
	*worst = w > *worst ? w : *worst;
	*flags |= ( acc->zero ? FLAG_ZERO_LENGTH : 0 ) | ( acc->nonfinite ? FLAG_NONFINITE : 0 );
}

/* The record of lane j of a half. Offsets are read two at a time with one 64-bit load (x86 is
 * little-endian: lane 2i in the low half): a half takes four loads for its eight offsets
 * instead of eight, and a sweep reads every offset twice (to load and to store). Offsets are
 * non-negative, so zero extension is exact. */
FORCE_INLINE float* record_at( float* packed, const int32_t* at, int j )
{
	uint64_t pair;
	memcpy( &pair, at + ( j & ~1 ), sizeof( pair ) );
	return packed + ( j & 1 ? (uint32_t) ( pair >> 32 ) : (uint32_t) pair );
}

/* Eight (x, y, z, w) records into one register per component: record 4j + r sits in 128-bit
 * lane j of register r, then a 4×4 transpose inside each 128-bit lane (as the AVX-512 path). */
FORCE_INLINE void load_records( float* packed, const int32_t* at, __m256* x, __m256* y, __m256* z, __m256* w )
{
	__m256 r0 = _mm256_insertf128_ps( _mm256_castps128_ps256( _mm_load_ps( record_at( packed, at, 0 ) ) ),
									  _mm_load_ps( record_at( packed, at, 4 ) ), 1 );
	__m256 r1 = _mm256_insertf128_ps( _mm256_castps128_ps256( _mm_load_ps( record_at( packed, at, 1 ) ) ),
									  _mm_load_ps( record_at( packed, at, 5 ) ), 1 );
	__m256 r2 = _mm256_insertf128_ps( _mm256_castps128_ps256( _mm_load_ps( record_at( packed, at, 2 ) ) ),
									  _mm_load_ps( record_at( packed, at, 6 ) ), 1 );
	__m256 r3 = _mm256_insertf128_ps( _mm256_castps128_ps256( _mm_load_ps( record_at( packed, at, 3 ) ) ),
									  _mm_load_ps( record_at( packed, at, 7 ) ), 1 );
	__m256d t0 = _mm256_castps_pd( _mm256_unpacklo_ps( r0, r1 ) ); /* x0 x1 y0 y1 per lane */
	__m256d t1 = _mm256_castps_pd( _mm256_unpackhi_ps( r0, r1 ) ); /* z0 z1 w0 w1 */
	__m256d t2 = _mm256_castps_pd( _mm256_unpacklo_ps( r2, r3 ) );
	__m256d t3 = _mm256_castps_pd( _mm256_unpackhi_ps( r2, r3 ) );
	*x = _mm256_castpd_ps( _mm256_unpacklo_pd( t0, t2 ) );
	*y = _mm256_castpd_ps( _mm256_unpackhi_pd( t0, t2 ) );
	*z = _mm256_castpd_ps( _mm256_unpacklo_pd( t1, t3 ) );
	*w = _mm256_castpd_ps( _mm256_unpackhi_pd( t1, t3 ) );
}

/* The inverse of load_records: four components into records, 8 stores of 128 bits. */
FORCE_INLINE void store_records( float* packed, const int32_t* at, __m256 x, __m256 y, __m256 z, __m256 w )
{
	__m256d t0 = _mm256_castps_pd( _mm256_unpacklo_ps( x, y ) );
	__m256d t1 = _mm256_castps_pd( _mm256_unpackhi_ps( x, y ) );
	__m256d t2 = _mm256_castps_pd( _mm256_unpacklo_ps( z, w ) );
	__m256d t3 = _mm256_castps_pd( _mm256_unpackhi_ps( z, w ) );
	__m256 r0 = _mm256_castpd_ps( _mm256_unpacklo_pd( t0, t2 ) );
	__m256 r1 = _mm256_castpd_ps( _mm256_unpackhi_pd( t0, t2 ) );
	__m256 r2 = _mm256_castpd_ps( _mm256_unpacklo_pd( t1, t3 ) );
	__m256 r3 = _mm256_castpd_ps( _mm256_unpackhi_pd( t1, t3 ) );
	_mm_store_ps( record_at( packed, at, 0 ), _mm256_castps256_ps128( r0 ) );
	_mm_store_ps( record_at( packed, at, 1 ), _mm256_castps256_ps128( r1 ) );
	_mm_store_ps( record_at( packed, at, 2 ), _mm256_castps256_ps128( r2 ) );
	_mm_store_ps( record_at( packed, at, 3 ), _mm256_castps256_ps128( r3 ) );
	_mm_store_ps( record_at( packed, at, 4 ), _mm256_extractf128_ps( r0, 1 ) );
	_mm_store_ps( record_at( packed, at, 5 ), _mm256_extractf128_ps( r1, 1 ) );
	_mm_store_ps( record_at( packed, at, 6 ), _mm256_extractf128_ps( r2, 1 ) );
	_mm_store_ps( record_at( packed, at, 7 ), _mm256_extractf128_ps( r3, 1 ) );
}

/* What the measuring part of a half leaves for the moving part: both ends and the factor f. */
typedef struct part_state
{
	__m256 ax, ay, az, aw, bx, by, bz, bw, f;
} part_state;

/* Loads both ends of the half at q and measures it (Jeong Eq. 13): the residual into acc and, unless
 * mode is MODE_MEASURE, the factor f (XPBD: and the multiplier λ; Jacobi: f stored per lane). */
FORCE_INLINE part_state measure_part( const block_context* ctx, int32_t q, block_mode mode, int xpbd, lane_accum* acc )
{
	part_state h;
	load_records( ctx->packed, ctx->ia + q, &h.ax, &h.ay, &h.az, &h.aw );
	load_records( ctx->packed, ctx->ib + q, &h.bx, &h.by, &h.bz, &h.bw );
	const __m256 zero = _mm256_setzero_ps();
	__m256 dx = _mm256_sub_ps( h.bx, h.ax ), dy = _mm256_sub_ps( h.by, h.ay ), dz = _mm256_sub_ps( h.bz, h.az );
	__m256 len2 =
		_mm256_add_ps( _mm256_add_ps( _mm256_mul_ps( dx, dx ), _mm256_mul_ps( dy, dy ) ), _mm256_mul_ps( dz, dz ) );
	__m256 len = _mm256_sqrt_ps( len2 );
	__m256 rest = _mm256_load_ps( ctx->rest + q );
	__m256 c = _mm256_sub_ps( len, rest ); /* Jeong Eq. 13 */
	acc->zero |= _mm256_movemask_ps( _mm256_cmp_ps( len, zero, _CMP_EQ_OQ ) );
	acc->nonfinite |= _mm256_movemask_ps( _mm256_cmp_ps( len, _mm256_set1_ps( FLT_MAX ), _CMP_NLE_UQ ) );
	__m256 wsum = _mm256_add_ps( h.aw, h.bw );
	__m256 lambda = zero, alpha = zero, residual = c;
	if ( xpbd )
	{
		alpha = _mm256_mul_ps( _mm256_set1_ps( ctx->alpha ), _mm256_load_ps( ctx->weight + q ) );
		lambda = _mm256_load_ps( ctx->lambda + q );
		residual = _mm256_add_ps( c, _mm256_mul_ps( alpha, lambda ) );
	}
	const __m256 magnitude = _mm256_castsi256_ps( _mm256_set1_epi32( 0x7fffffff ) );
	acc->worst = _mm256_max_ps( acc->worst, _mm256_div_ps( _mm256_and_ps( residual, magnitude ), rest ) );
	h.f = zero;
	if ( mode == MODE_MEASURE )
	{
		return h;
	}
	/* a masked-off lane's quotient (0/0 or x/0) is replaced by zero, as the AVX-512 maskz_div */
	if ( xpbd )
	{
		__m256 denominator = _mm256_add_ps( wsum, alpha );
		__m256 movable = _mm256_cmp_ps( denominator, zero, _CMP_GT_OQ );
		__m256 numerator = _mm256_sub_ps( _mm256_sub_ps( zero, c ), _mm256_mul_ps( alpha, lambda ) );
		__m256 dlambda = _mm256_and_ps( movable, _mm256_div_ps( numerator, denominator ) );
		_mm256_store_ps( ctx->lambda + q, _mm256_add_ps( lambda, dlambda ) );
		h.f = _mm256_div_ps( _mm256_sub_ps( zero, dlambda ), len );
	}
	else
	{
		__m256 movable = _mm256_cmp_ps( wsum, zero, _CMP_GT_OQ );
		h.f = _mm256_and_ps(
			movable, _mm256_div_ps( _mm256_mul_ps( _mm256_set1_ps( ctx->k ), c ), _mm256_mul_ps( wsum, len ) ) );
	}
	if ( mode == MODE_JACOBI )
	{
		_mm256_store_ps( ctx->factor + q, h.f );
	}
	return h;
}

/* The moving part of a Gauss–Seidel half: p_a += (w_a f) d, p_b −= (w_b f) d (Jeong Eq. 13), stored.
 * d = p_b − p_a again, the same operation on the same values as in measure_part, so the same
 * bits; recomputing it keeps three registers fewer alive between the two parts. */
FORCE_INLINE void move_part( const block_context* ctx, int32_t q, const part_state* h )
{
	__m256 dx = _mm256_sub_ps( h->bx, h->ax ), dy = _mm256_sub_ps( h->by, h->ay ), dz = _mm256_sub_ps( h->bz, h->az );
	__m256 fa = _mm256_mul_ps( h->aw, h->f ), fb = _mm256_mul_ps( h->bw, h->f );
	store_records( ctx->packed, ctx->ia + q, _mm256_add_ps( h->ax, _mm256_mul_ps( fa, dx ) ),
				   _mm256_add_ps( h->ay, _mm256_mul_ps( fa, dy ) ), _mm256_add_ps( h->az, _mm256_mul_ps( fa, dz ) ),
				   h->aw );
	store_records( ctx->packed, ctx->ib + q, _mm256_sub_ps( h->bx, _mm256_mul_ps( fb, dx ) ),
				   _mm256_sub_ps( h->by, _mm256_mul_ps( fb, dy ) ), _mm256_sub_ps( h->bz, _mm256_mul_ps( fb, dz ) ),
				   h->bw );
}

FORCE_INLINE void touch_part( const block_context* ctx, int32_t q )
{
	__m256 ax, ay, az, aw, bx, by, bz, bw;
	load_records( ctx->packed, ctx->ia + q, &ax, &ay, &az, &aw );
	load_records( ctx->packed, ctx->ib + q, &bx, &by, &bz, &bw );
	const __m256 one = _mm256_set1_ps( ctx->one );
	store_records( ctx->packed, ctx->ia + q, _mm256_mul_ps( ax, one ), _mm256_mul_ps( ay, one ),
				   _mm256_mul_ps( az, one ), aw );
	store_records( ctx->packed, ctx->ib + q, _mm256_mul_ps( bx, one ), _mm256_mul_ps( by, one ),
				   _mm256_mul_ps( bz, one ), bw );
}

/* Constraints per measure/move part: half a block. */
#define PART ( LANES / 2 )

#else

/* Portable build (no AVX): the same operations one lane at a time. Lanes of a block share
 * no particle, so doing them in sequence gives the bits the SIMD build gives. */
typedef struct lane_accum
{
	float worst;
	int zero, nonfinite;
} lane_accum;

FORCE_INLINE lane_accum lane_accum_start( void )
{
	lane_accum acc = { 0.0f, 0, 0 };
	return acc;
}

FORCE_INLINE void lane_accum_finish( const lane_accum* acc, float* worst, int32_t* flags )
{
	*worst = acc->worst > *worst ? acc->worst : *worst;
	*flags |= ( acc->zero ? FLAG_ZERO_LENGTH : 0 ) | ( acc->nonfinite ? FLAG_NONFINITE : 0 );
}

FORCE_INLINE void project_block( const block_context* ctx, int32_t q0, block_mode mode, int xpbd, lane_accum* acc )
{
	for ( int32_t q = q0; q < q0 + LANES; ++q )
	{
		float* pa = ctx->packed + ctx->ia[q];
		float* pb = ctx->packed + ctx->ib[q];
		if ( mode == MODE_TOUCH )
		{
			for ( int j = 0; j < 3; ++j )
			{
				pa[j] = pa[j] * ctx->one;
				pb[j] = pb[j] * ctx->one;
			}
			continue;
		}
		float dx = pb[0] - pa[0], dy = pb[1] - pa[1], dz = pb[2] - pa[2];
		float len = sqrtf( ( dx * dx + dy * dy ) + dz * dz );
		float rest = ctx->rest[q];
		float c = len - rest; /* Jeong Eq. 13 */
		acc->zero |= len == 0.0f;
		acc->nonfinite |= !( len <= FLT_MAX );
		float wsum = pa[3] + pb[3];
		float lambda = xpbd ? ctx->lambda[q] : 0.0f;
		float alpha = xpbd ? ctx->alpha * ctx->weight[q] : 0.0f;
		float residual = xpbd ? c + alpha * lambda : c;
		float strain = fabsf( residual ) / rest;
		acc->worst = strain > acc->worst ? strain : acc->worst;
		if ( mode == MODE_MEASURE )
		{
			continue;
		}
		float f;
		if ( xpbd )
		{
			float denominator = wsum + alpha;
			float dlambda = denominator > 0.0f ? ( ( 0.0f - c ) - alpha * lambda ) / denominator : 0.0f;
			ctx->lambda[q] = lambda + dlambda;
			f = ( 0.0f - dlambda ) / len;
		}
		else
		{
			f = wsum > 0.0f ? ( ctx->k * c ) / ( wsum * len ) : 0.0f;
		}
		if ( mode == MODE_JACOBI )
		{
			ctx->factor[q] = f;
			continue;
		}
		float fa = pa[3] * f, fb = pb[3] * f;
		pa[0] = pa[0] + fa * dx, pa[1] = pa[1] + fa * dy, pa[2] = pa[2] + fa * dz;
		pb[0] = pb[0] - fb * dx, pb[1] = pb[1] - fb * dy, pb[2] = pb[2] - fb * dz;
	}
}

#endif

#if defined( __AVX512F__ ) || defined( __AVX__ )
/* Lanes [first, last) of one color of one item, a multiple of LANES, in parts of PART lanes.
 *
 * Gauss–Seidel is software-pipelined by one part: the next part is measured before this one
 * moves. Measuring (loads, transposes, √, two divisions) is a dependency chain of some 60 cycles
 * and a part's moves wait at its end; issued in program order they filled the out-of-order
 * window (llvm-mca's Zen 3 model: the 64-entry floating-point scheduler full most of the time),
 * so a core worked on about one part at a time. Measured one part ahead, a part's moves find f
 * ready. On the maple at one thread this took an AVX2 sweep from 2.2 to 1.8 times its floor
 * (sere_pbd_touch_sweeps) and an AVX-512 sweep (one block a part) from 1.6 to 1.3 (CPU time). All lanes
 * of one color share no particle, so reading the next part before this one is stored reads the
 * same values. */
FORCE_INLINE void project_segment( const block_context* ctx, int32_t first, int32_t last, block_mode mode, int xpbd,
								   lane_accum* acc )
{
	if ( mode != MODE_GAUSS_SEIDEL )
	{
		for ( int32_t q = first; q < last; q += PART )
		{
			if ( mode == MODE_TOUCH )
			{
				touch_part( ctx, q );
			}
			else
			{
				measure_part( ctx, q, mode, xpbd, acc );
			}
		}
		return;
	}
	if ( first == last )
	{
		return;
	}
	part_state current = measure_part( ctx, first, mode, xpbd, acc );
	for ( int32_t q = first; q + PART < last; q += PART )
	{
		part_state next = measure_part( ctx, q + PART, mode, xpbd, acc );
		move_part( ctx, q, &current );
		current = next;
	}
	move_part( ctx, last - PART, &current );
}
#else
/* Lanes [first, last) of one color of one item, a multiple of LANES: block after block. */
FORCE_INLINE void project_segment( const block_context* ctx, int32_t first, int32_t last, block_mode mode, int xpbd,
								   lane_accum* acc )
{
	for ( int32_t q = first; q < last; q += LANES )
	{
		project_block( ctx, q, mode, xpbd, acc );
	}
}
#endif

/* ---------------------------------------------------------------------------------------
 * Threads: work claiming and the barrier. */

typedef struct wait_state
{
	double start;
	unsigned spins;
} wait_state;

/* One turn of a wait loop. Spin while the wait is short (a sweep is tens of µs); past
 * SPIN_SECONDS another thread has most likely lost its core to some other process, so nap
 * instead: an idle core lets the scheduler move that thread over, where spinning (or
 * yielding) would keep it queued behind the other process for a whole time slice
 * (milliseconds). */
static void wait_step( wait_state* wait )
{
	if ( ++wait->spins % 1024 == 0 )
	{
		double now = omp_get_wtime();
		wait->start = wait->start < 0.0 ? now : wait->start;
		if ( now - wait->start > SPIN_SECONDS )
		{
			const struct timespec nap = { 0, NAP_NANOSECONDS };
			nanosleep( &nap, NULL );
		}
	}
}

/* Waits until item `item` has been projected in sweep `number` of this call. */
static void wait_done( sere_pbd* pbd, int32_t item, int32_t number )
{
	wait_state wait = { -1.0, 0 };
	while ( atomic_load_explicit( &pbd->done[item].value, memory_order_acquire ) < number )
	{
		wait_step( &wait );
	}
}

static void barrier_wait( spin_barrier* barrier, int threads )
{
	if ( threads == 1 )
	{
		return;
	}
	unsigned generation = atomic_load_explicit( &barrier->generation, memory_order_relaxed );
	if ( atomic_fetch_add_explicit( &barrier->arrived, 1u, memory_order_acq_rel ) == (unsigned) threads - 1 )
	{
		atomic_store_explicit( &barrier->arrived, 0u, memory_order_relaxed );
		atomic_store_explicit( &barrier->generation, generation + 1u, memory_order_release );
		return;
	}
	wait_state wait = { -1.0, 0 };
	while ( atomic_load_explicit( &barrier->generation, memory_order_acquire ) == generation )
	{
		wait_step( &wait );
	}
}

/* Publishes this thread's result of a pass, waits for all, and returns the combined result
 * (the same on every thread, so all take the same branch next). Max is exact in any order. */
static void exchange( sere_pbd* pbd, int t, int threads, int* parity, float* worst, int32_t* flags )
{
	pbd->threads[t].worst[*parity] = *worst;
	pbd->threads[t].flags[*parity] = *flags;
	barrier_wait( pbd->barrier, threads );
	float all_worst = 0.0f;
	int32_t all_flags = 0;
	for ( int u = 0; u < threads; ++u )
	{
		float w = pbd->threads[u].worst[*parity];
		all_worst = w > all_worst ? w : all_worst;
		all_flags |= pbd->threads[u].flags[*parity];
	}
	*parity ^= 1;
	*worst = all_worst;
	*flags = all_flags;
}

/* Thread u's work list in a pass. In a sweep: its share of the bands [r0, r1), then the cuts
 * c ∈ [r0, min(r1, R − 1)) below them (cut c joins bands c and c + 1), the even ones before
 * the odd ones. In any other pass: its share of all items. Either way it starts with what it
 * packed, so the records are in its own cache. */
typedef struct work_list
{
	int32_t first, count;		 /* bands (a sweep) or items (any other pass) */
	int32_t cut_first, cut_last; /* a sweep's cuts */
	int32_t length;
} work_list;

static work_list work_of( const sere_pbd* pbd, pass_kind kind, int u, int threads )
{
	work_list w = { 0, 0, 0, 0, 0 };
	const int32_t n = kind == PASS_SWEEP ? pbd->bands : pbd->items;
	w.first = (int32_t) ( (int64_t) n * u / threads );
	w.count = (int32_t) ( (int64_t) n * ( u + 1 ) / threads ) - w.first;
	w.length = w.count;
	if ( kind == PASS_SWEEP && w.count > 0 )
	{
		const int32_t end = w.first + w.count;
		w.cut_first = w.first;
		w.cut_last = end < pbd->bands - 1 ? end : pbd->bands - 1;
		w.length += w.cut_last - w.cut_first;
	}
	return w;
}

/* The j-th item of a list. */
static int32_t work_item( const sere_pbd* pbd, const work_list* w, int32_t j )
{
	if ( j < w->count )
	{
		return w->first + j;
	}
	j -= w->count;
	const int32_t first_even = ( w->cut_first + 1 ) & ~1;
	const int32_t evens = ( w->cut_last - first_even + 1 ) / 2;
	const int32_t cut = j < evens ? first_even + 2 * j : ( w->cut_first | 1 ) + 2 * ( j - evens );
	return pbd->bands + cut;
}

/* Before cut c of sweep `number`, what it reads must be final: bands c and c + 1 and, for an
 * odd c, the even cuts c − 1 and c + 1 that share its bands. Together with the exchange that
 * ends each sweep this keeps the order of one thread (bands, even cuts, odd cuts) for every
 * pair of items that share a particle, so the result does not depend on the threads, while
 * a sweep has one barrier instead of one per group. */
static void wait_cut_inputs( sere_pbd* pbd, int32_t cut, int32_t number )
{
	const int32_t bands = pbd->bands;
	wait_done( pbd, cut, number );
	wait_done( pbd, cut + 1, number );
	if ( cut & 1 )
	{
		wait_done( pbd, bands + cut - 1, number );
		if ( cut + 1 < bands - 1 )
		{
			wait_done( pbd, bands + cut + 1, number );
		}
	}
}

/* One item, color after color (all lanes of one block have one color), with its own copy of
 * the loop for each mode: with mode and xpbd constant the branches leave the loop and the
 * accumulator stays in registers. The context is copied too: stores through its float pointers
 * could otherwise alias it, and every block reloaded its pointers. */
FORCE_INLINE void project_colors( const block_context* ctx, const int32_t* segment, int32_t colors, block_mode mode,
								  int xpbd, lane_accum* acc )
{
	const block_context local_ctx = *ctx;
	lane_accum local = *acc;
	for ( int32_t c = 0; c < colors; ++c )
	{
		project_segment( &local_ctx, segment[c], segment[c + 1], mode, xpbd, &local );
	}
	*acc = local;
}

/* segment: the item's colors + 1 lane offsets. */
static void project_item( const block_context* ctx, const int32_t* segment, int32_t colors, block_mode mode, int xpbd,
						  lane_accum* acc )
{
	switch ( mode )
	{
		case MODE_GAUSS_SEIDEL:
			xpbd ? project_colors( ctx, segment, colors, MODE_GAUSS_SEIDEL, 1, acc )
				 : project_colors( ctx, segment, colors, MODE_GAUSS_SEIDEL, 0, acc );
			break;
		case MODE_JACOBI:
			xpbd ? project_colors( ctx, segment, colors, MODE_JACOBI, 1, acc )
				 : project_colors( ctx, segment, colors, MODE_JACOBI, 0, acc );
			break;
		case MODE_MEASURE:
			xpbd ? project_colors( ctx, segment, colors, MODE_MEASURE, 1, acc )
				 : project_colors( ctx, segment, colors, MODE_MEASURE, 0, acc );
			break;
		case MODE_TOUCH:
			project_colors( ctx, segment, colors, MODE_TOUCH, 0, acc );
			break;
	}
}

/* Thread t takes the items of its own list in order, then helps the other threads with
 * theirs, so a thread on a slower core does less. Which thread projects an item never changes
 * the result (wait_cut_inputs). A thread that waits on a cut holds only an odd cut or an even
 * one waiting on bands, and owners take their lists in order (bands, even, odd), so some
 * thread can always go on. `number` is the sweep of this call (a PASS_SWEEP). */
static void run_pass( sere_pbd* pbd, const block_context* ctx, pass_kind kind, int parity, int32_t number,
					  block_mode mode, int xpbd, int t, int threads, float* worst, int32_t* flags )
{
	/* The other parity's counters are idle until the exchange that ends this pass. */
	atomic_store_explicit( &pbd->counters[( 1 - parity ) * MAX_THREADS + t].value, 0, memory_order_relaxed );
	const int32_t colors = pbd->colors;
	lane_accum acc = lane_accum_start();
	for ( int v = 0; v < threads; ++v )
	{
		const int u = ( t + v ) % threads;
		const work_list w = work_of( pbd, kind, u, threads );
		atomic_int* next = &pbd->counters[parity * MAX_THREADS + u].value;
		for ( ;; )
		{
			int32_t j = atomic_fetch_add_explicit( next, 1, memory_order_relaxed );
			if ( j >= w.length )
			{
				break;
			}
			const int32_t item = kind == PASS_SWEEP ? work_item( pbd, &w, j ) : w.first + j;
			if ( kind == PASS_SWEEP && item >= pbd->bands )
			{
				wait_cut_inputs( pbd, item - pbd->bands, number );
			}
			project_item( ctx, pbd->segment + item * colors, colors, mode, xpbd, &acc );
			if ( kind == PASS_SWEEP )
			{
				atomic_store_explicit( &pbd->done[item].value, number, memory_order_release );
			}
		}
	}
	lane_accum_finish( &acc, worst, flags );
}

/* Thread t's share [first, last) of n. */
static void share( int32_t n, int t, int threads, int32_t* first, int32_t* last )
{
	*first = (int32_t) ( (int64_t) n * t / threads );
	*last = (int32_t) ( (int64_t) n * ( t + 1 ) / threads );
}

/* Caller's arrays into records. Thread t writes the records of the bands it starts the
 * band phase with, in slot order: whole cache lines that no other thread writes (written in
 * the caller's order, the two threads' records shared lines, and at 2 threads the false
 * sharing cost more than the rest of a call), and that this thread then reads first. Every
 * value is checked once, on the records just written. */
static int32_t pack( sere_pbd* pbd, const float* px, const float* py, const float* pz, const float* inv_m, int t,
					 int threads )
{
	const int32_t first = pbd->band_start[(int64_t) pbd->bands * t / threads];
	const int32_t last = pbd->band_start[(int64_t) pbd->bands * ( t + 1 ) / threads];
	const int32_t* particle = pbd->particle;
	float* packed = pbd->packed[0];
	for ( int32_t s = first; s < last; ++s )
	{
		const int32_t i = particle[s];
		float* record = packed + 4 * s;
		record[0] = px[i], record[1] = py[i], record[2] = pz[i], record[3] = inv_m[i];
	}
	/* Flags as 0/1 per record, combined after: this form vectorizes (a flag-valued select per
	 * value did not, and cost twice the packing). */
	int32_t nonfinite = 0, negative = 0;
#pragma omp simd reduction( | : nonfinite, negative )
	for ( int32_t s = first; s < last; ++s )
	{
		const float* record = packed + 4 * s;
		nonfinite |= !( fabsf( record[0] ) <= FLT_MAX ) | !( fabsf( record[1] ) <= FLT_MAX ) |
					 !( fabsf( record[2] ) <= FLT_MAX ) | !( fabsf( record[3] ) <= FLT_MAX );
		negative |= record[3] < 0.0f;
	}
	return ( nonfinite ? FLAG_NONFINITE : 0 ) | ( negative ? FLAG_NEGATIVE_MASS : 0 );
}

static void unpack( const float* packed, const int32_t* slot, int32_t n, float* px, float* py, float* pz, int t,
					int threads )
{
	int32_t first, last;
	share( n, t, threads, &first, &last );
	for ( int32_t i = first; i < last; ++i )
	{
		const float* record = packed + 4 * slot[i];
		px[i] = record[0], py[i] = record[1], pz[i] = record[2];
	}
}

/* Jacobi: every particle of thread t's share moves from its old record to a new one by
 * ω/n_i · w_i Σ f_q (p_other − p_i) over its constraints q, summed in lane order (both ends
 * of a constraint move along their own d, which is how −w_b f d reads from b's side). */
static void jacobi_apply( sere_pbd* pbd, const float* old, float* next, float omega, int t, int threads )
{
	int32_t first, last;
	share( pbd->particle_count, t, threads, &first, &last );
	const float* factor = pbd->factor;
	const int32_t* adjacency = pbd->adjacency;
	for ( int32_t s = first; s < last; ++s )
	{
		const float* p = old + 4 * s;
		float sx = 0.0f, sy = 0.0f, sz = 0.0f;
		for ( int32_t e = pbd->adjacency_offset[s]; e < pbd->adjacency_offset[s + 1]; ++e )
		{
			float f = factor[adjacency[2 * e]];
			const float* o = old + adjacency[2 * e + 1];
			sx += f * ( o[0] - p[0] ), sy += f * ( o[1] - p[1] ), sz += f * ( o[2] - p[2] );
		}
		float scale = ( omega * pbd->inv_degree[s] ) * p[3];
		float* n = next + 4 * s;
		n[0] = p[0] + scale * sx, n[1] = p[1] + scale * sy, n[2] = p[2] + scale * sz, n[3] = p[3];
	}
}

static sere_status status_of( int32_t flags )
{
	if ( flags & FLAG_NEGATIVE_MASS )
	{
		return SERE_ERR_ARGUMENT;
	}
	if ( flags & FLAG_ZERO_LENGTH )
	{
		return SERE_ERR_GEOMETRY;
	}
	return flags & FLAG_NONFINITE ? SERE_ERR_NONFINITE : SERE_OK;
}

typedef enum solver
{
	SOLVER_GAUSS_SEIDEL,
	SOLVER_JACOBI,
	SOLVER_TOUCH,
} solver;

typedef struct solve_setup
{
	solver kind;
	float k, alpha, omega, tolerance;
	int32_t max_iterations;
	int xpbd, warm;
	float rho;	   /* Chebyshev ρ, 0: off */
	int32_t delay; /* Chebyshev: plain sweeps before the first extrapolation */
} solve_setup;

typedef struct solve_result
{
	int32_t iterations, flags;
	float strain;
	int converged;
} solve_result;

/* One thread's part of sweep `number` of a Gauss–Seidel (or touch) call; returns the
 * combined result of the sweep. */
static void sweep( sere_pbd* pbd, const block_context* ctx, block_mode mode, int xpbd, int t, int threads, int* parity,
				   int32_t number, float* worst, int32_t* flags )
{
	run_pass( pbd, ctx, PASS_SWEEP, *parity, number, mode, xpbd, t, threads, worst, flags );
	exchange( pbd, t, threads, parity, worst, flags );
}

/* Chebyshev semi-iteration (Wang 2015): x_{k+1} = ω_{k+1} (x̂_{k+1} − x_{k−1}) + x_{k−1},
 * x̂_{k+1} the sweep's result in the records, x_{k−1} in history[*older]; with XPBD the same
 * combination of the multipliers, so each position stays the inertia anchor plus the
 * multipliers' corrections (Δx = M⁻¹ ∇Cᵀ Δλ is linear in Δλ for fixed gradients). ω = 1 only
 * records x_{k+1} = x̂_{k+1} (ω (x̂ − x) + x would round it). The new iterate overwrites
 * x_{k−1}, which becomes x_k for the next sweep. Thread t takes its share of the floats; a
 * barrier follows, since any thread may project any item next. */
static void extrapolate( sere_pbd* pbd, float omega, int xpbd, int* older, int t, int threads )
{
	int32_t first, last;
	float* restrict p = pbd->packed[0];
	float* restrict h = pbd->history[*older];
	share( 4 * pbd->slot_count, t, threads, &first, &last );
	if ( omega == 1.0f )
	{
		memcpy( h + first, p + first, sizeof( float ) * (size_t) ( last - first ) );
	}
	else
	{
		for ( int32_t s = first; s < last; ++s )
		{
			float n = omega * ( p[s] - h[s] ) + h[s];
			p[s] = n, h[s] = n;
		}
	}
	if ( xpbd )
	{
		float* restrict l = pbd->lambda;
		float* restrict g = pbd->lambda_history[*older];
		share( pbd->lanes, t, threads, &first, &last );
		if ( omega == 1.0f )
		{
			memcpy( g + first, l + first, sizeof( float ) * (size_t) ( last - first ) );
		}
		else
		{
			for ( int32_t q = first; q < last; ++q )
			{
				float n = omega * ( l[q] - g[q] ) + g[q];
				l[q] = n, g[q] = n;
			}
		}
	}
	*older ^= 1;
	barrier_wait( pbd->barrier, threads );
}

/* Gauss–Seidel sweeps until converged (and verified) or the cap; runs on every thread. */
static solve_result gauss_seidel( sere_pbd* pbd, const block_context* ctx, const solve_setup* setup, int t, int threads,
								  int* parity )
{
	solve_result result = { 0, 0, 0.0f, 0 };
	const block_mode mode = setup->kind == SOLVER_TOUCH ? MODE_TOUCH : MODE_GAUSS_SEIDEL;
	/* Chebyshev weights (Wang 2015), the same sequence on every thread. */
	const double rho2 = (double) setup->rho * (double) setup->rho;
	double omega = 1.0;
	int older = 0;
	while ( result.iterations < setup->max_iterations )
	{
		float worst = 0.0f;
		int32_t flags = 0;
		sweep( pbd, ctx, mode, setup->xpbd, t, threads, parity, result.iterations + 1, &worst, &flags );
		result.iterations += 1, result.flags = flags, result.strain = worst;
		if ( flags != 0 )
		{
			break;
		}
		/* The floor runs its sweeps to the cap, exchanges included. */
		if ( setup->kind != SOLVER_TOUCH && worst < setup->tolerance )
		{
			/* Residuals were taken before each projection; check the positions left. */
			worst = 0.0f;
			run_pass( pbd, ctx, PASS_ALL, *parity, 0, MODE_MEASURE, setup->xpbd, t, threads, &worst, &flags );
			exchange( pbd, t, threads, parity, &worst, &flags );
			result.flags = flags;
			if ( flags != 0 || worst < setup->tolerance )
			{
				result.strain = worst, result.converged = flags == 0;
				break;
			}
		}
		if ( setup->rho > 0.0f && result.iterations < setup->max_iterations )
		{
			const int32_t k = result.iterations;
			omega = k <= setup->delay		? 1.0
					: k == setup->delay + 1 ? 2.0 / ( 2.0 - rho2 )
											: 4.0 / ( 4.0 - rho2 * omega );
			extrapolate( pbd, (float) omega, setup->xpbd, &older, t, threads );
		}
	}
	return result;
}

/* Jacobi sweeps, alternating the two record buffers; *front ends on the one holding the
 * result. */
static solve_result jacobi( sere_pbd* pbd, block_context* ctx, const solve_setup* setup, int t, int threads,
							int* parity, int* front )
{
	solve_result result = { 0, 0, 0.0f, 0 };
	while ( result.iterations < setup->max_iterations )
	{
		float worst = 0.0f;
		int32_t flags = 0;
		ctx->packed = pbd->packed[*front];
		run_pass( pbd, ctx, PASS_ALL, *parity, 0, MODE_JACOBI, setup->xpbd, t, threads, &worst, &flags );
		exchange( pbd, t, threads, parity, &worst, &flags );
		result.iterations += 1, result.flags = flags, result.strain = worst;
		/* Measured on the positions as they are: converged means exactly that. */
		if ( flags != 0 || worst < setup->tolerance )
		{
			result.converged = flags == 0;
			break;
		}
		jacobi_apply( pbd, pbd->packed[*front], pbd->packed[1 - *front], setup->omega, t, threads );
		*front = 1 - *front;
		barrier_wait( pbd->barrier, threads );
	}
	return result;
}

static sere_status solve( sere_pbd* pbd, float* px, float* py, float* pz, const float* inv_m, const solve_setup* setup,
						  sere_pbd_report* report )
{
	int requested = sere_team_default();
	requested = requested < 1 ? 1 : requested > MAX_THREADS ? MAX_THREADS : requested;
	solve_result outcome = { 0, 0, 0.0f, 0 };
	/* One parallel region per call; inside it every thread follows the same control flow,
	 * driven by values combined in exchange(). */
#pragma omp parallel num_threads( requested )
	{
		const int t = omp_get_thread_num(), threads = omp_get_num_threads();
		block_context ctx = {
			.packed = pbd->packed[0],
			.ia = pbd->ia,
			.ib = pbd->ib,
			.rest = pbd->rest,
			.lambda = pbd->lambda,
			.weight = pbd->weight,
			.factor = pbd->factor,
			.k = setup->k,
			.alpha = setup->alpha,
			.one = pbd->one,
		};
		int parity = 0, front = 0;
		float worst = 0.0f;
		int32_t flags = pack( pbd, px, py, pz, inv_m, t, threads );
		if ( setup->xpbd && !setup->warm )
		{
			int32_t first, last;
			share( pbd->lanes, t, threads, &first, &last );
			memset( pbd->lambda + first, 0, sizeof( float ) * (size_t) ( last - first ) );
		}
		/* Work lists from their start; no item projected yet in this call. The exchange below
		 * publishes both before any pass. */
		atomic_store_explicit( &pbd->counters[t].value, 0, memory_order_relaxed );
		atomic_store_explicit( &pbd->counters[MAX_THREADS + t].value, 0, memory_order_relaxed );
		for ( int32_t item = t; item < pbd->items; item += threads )
		{
			atomic_store_explicit( &pbd->done[item].value, 0, memory_order_relaxed );
		}
		exchange( pbd, t, threads, &parity, &worst, &flags );
		solve_result result = { 0, flags, 0.0f, 0 };
		if ( flags == 0 )
		{
			result = setup->kind == SOLVER_JACOBI ? jacobi( pbd, &ctx, setup, t, threads, &parity, &front )
												  : gauss_seidel( pbd, &ctx, setup, t, threads, &parity );
		}
		if ( result.flags == 0 )
		{
			unpack( pbd->packed[front], pbd->slot, pbd->particle_count, px, py, pz, t, threads );
		}
		if ( t == 0 )
		{
			outcome = result;
		}
	}
	report->iterations = outcome.iterations;
	report->max_strain = outcome.strain;
	report->hit_cap = !outcome.converged;
	return status_of( outcome.flags );
}

static sere_status check_call( const sere_pbd* pbd, const float* px, const float* py, const float* pz,
							   const float* inv_m, const sere_pbd_params* params, sere_pbd_report* report )
{
	if ( pbd == NULL || px == NULL || py == NULL || pz == NULL || inv_m == NULL || params == NULL || report == NULL ||
		 !( params->stiffness >= 0.0f && params->stiffness <= 1.0f ) || !( params->tolerance > 0.0f ) ||
		 params->max_iterations < 1 || !( params->compliance >= 0.0f && params->compliance <= FLT_MAX ) ||
		 !( params->chebyshev_rho >= 0.0f && params->chebyshev_rho < 1.0f ) || params->chebyshev_delay < 2 )
	{
		return SERE_ERR_ARGUMENT;
	}
	if ( params->compliance > 0.0f )
	{
		float alpha = params->compliance / ( params->dt * params->dt );
		if ( !( params->dt > 0.0f ) || !( alpha <= FLT_MAX ) )
		{
			return SERE_ERR_ARGUMENT;
		}
	}
	return pbd->rest_valid ? SERE_OK : SERE_ERR_GEOMETRY;
}

static solve_setup setup_of( const sere_pbd_params* params, solver kind )
{
	solve_setup setup = {
		.kind = kind,
		.k = params->stiffness,
		.alpha = params->compliance > 0.0f ? params->compliance / ( params->dt * params->dt ) : 0.0f,
		.omega = params->relaxation,
		.tolerance = params->tolerance,
		.max_iterations = params->max_iterations,
		.xpbd = params->compliance > 0.0f,
		.warm = params->warm,
		.rho = params->chebyshev_rho,
		.delay = params->chebyshev_delay,
	};
	return setup;
}

sere_status sere_pbd_project( sere_pbd* pbd, float* px, float* py, float* pz, const float* inv_m,
							  const sere_pbd_params* params, sere_pbd_report* report )
{
	if ( report != NULL )
	{
		memset( report, 0, sizeof( *report ) );
	}
	sere_status status = check_call( pbd, px, py, pz, inv_m, params, report );
	if ( status != SERE_OK )
	{
		return status;
	}
	solve_setup setup = setup_of( params, SOLVER_GAUSS_SEIDEL );
	if ( params->linear_stiffness )
	{
		/* (1 − k')^n = 1 − k after n sweeps. */
		setup.k = (float) ( 1.0 - pow( 1.0 - (double) params->stiffness, 1.0 / (double) params->max_iterations ) );
	}
	return solve( pbd, px, py, pz, inv_m, &setup, report );
}

sere_status sere_pbd_project_jacobi( sere_pbd* pbd, float* px, float* py, float* pz, const float* inv_m,
									 const sere_pbd_params* params, sere_pbd_report* report )
{
	if ( report != NULL )
	{
		memset( report, 0, sizeof( *report ) );
	}
	sere_status status = check_call( pbd, px, py, pz, inv_m, params, report );
	if ( status != SERE_OK )
	{
		return status;
	}
	if ( !( params->relaxation > 0.0f && params->relaxation < 2.0f ) || params->linear_stiffness ||
		 params->chebyshev_rho > 0.0f )
	{
		return SERE_ERR_ARGUMENT;
	}
	solve_setup setup = setup_of( params, SOLVER_JACOBI );
	return solve( pbd, px, py, pz, inv_m, &setup, report );
}

sere_status sere_pbd_touch_sweeps( sere_pbd* pbd, float* px, float* py, float* pz, const float* inv_m, int32_t sweeps )
{
	if ( pbd == NULL || px == NULL || py == NULL || pz == NULL || inv_m == NULL || sweeps < 1 )
	{
		return SERE_ERR_ARGUMENT;
	}
	solve_setup setup = { .kind = SOLVER_TOUCH, .k = 1.0f, .omega = 1.0f, .tolerance = 1.0f, .max_iterations = sweeps };
	sere_pbd_report report;
	return solve( pbd, px, py, pz, inv_m, &setup, &report );
}

sere_status sere_pbd_touch( sere_pbd* pbd, float* px, float* py, float* pz, const float* inv_m )
{
	return sere_pbd_touch_sweeps( pbd, px, py, pz, inv_m, 1 );
}
