/* _GNU_SOURCE: sched_getaffinity for core/internal/team.h. */
#define _GNU_SOURCE

#include "solve/vbd.h"

#include "core/internal/simd.h"
#include "core/internal/team.h"

#include <float.h>
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

enum
{
	MAX_COLORS = 64, /* a particle's neighbours' colors are bits of one word */
	CHUNK_ROWS = 16, /* block_step's rows a pass: 4 KiB of a block's spring ends at 16 lanes */
	FLAG_NONFINITE = 1,
	FLAG_NEGATIVE_MASS = 2,
};

/* A spring shorter than this is measured as this long, so that 1/|d|² stays finite in float: a
 * spring whose ends coincide then pulls along no axis, and a padding lane (stiffness 0, reading
 * the dummy record) adds exact zeros. */
#define TINY_LENGTH 1e-18f

/* Per-thread results of a sweep, by sweep parity (a fast thread writes the next sweep's while a
 * slow one still reads this one's). One cache line each. */
typedef struct thread_slot
{
	_Alignas( 64 ) float move2[2];
	int32_t flags[2];
} thread_slot;

struct sere_vbd
{
	int32_t thread_count;
	int32_t particle_count, spring_count;
	int32_t colors, blocks, slots, rows;
	int32_t color_block[MAX_COLORS + 1]; /* color c owns blocks [color_block[c], color_block[c+1]) */
	int32_t* block_row;					 /* blocks + 1: block b sweeps rows [block_row[b], block_row[b+1]) */
	int32_t* slot_of;					 /* per particle */
	int32_t* particle_of;				 /* per slot: the particle, or −1 for padding */
	/* A row holds one spring of every lane of its block: the neighbour's record (an offset in
	 * floats; padding reads the dummy record after the last slot), the spring (padding: the
	 * sentinel spring_count, whose rest length is 1 and weight +∞), its rest length and stiffness
	 * (0 for padding, which then adds nothing). */
	int32_t *neighbour, *spring;
	float *rest, *stiffness;
	/* Particle records (x, y, z, movable: 1 or 0) by slot, slots + 1 (the dummy); the Chebyshev history. */
	float *record, *history[2];
	float *mass, *tx, *ty, *tz, *push; /* by slot */
	/* By slot: the last step's answer less its prediction, where a warm start begins the next
	 * step's sweeps (sere_vbd_params.warm_start); valid once a step has succeeded. */
	float *cx, *cy, *cz;
	int correction_valid;
	/* The springs as given, for the residual: ends, rest lengths, weights, and each particle's
	 * springs (adjacency[offset[i] .. offset[i+1])). */
	int32_t *a, *b, *offset, *adjacency;
	float *spring_rest, *spring_weight;
	int rest_valid, push_valid;
	int rest_stale;		  /* rest lengths changed since the rows took them */
	int stiffness_stale;  /* weights changed since the rows' stiffnesses were computed */
	float inverse_alpha;  /* the dt²/α the rows' stiffnesses were computed with */
	thread_slot* results; /* SERE_MAX_THREADS */
	sere_spin_barrier* barrier;
	sere_team_tuner tuner; /* the team or one thread, by the seconds a sweep takes (team.h) */
};

sere_vbd_params sere_vbd_params_default( void )
{
	return ( sere_vbd_params ){ .dt = 0.002f,
								.compliance = 4e-6f,
								.tolerance = 1e-6f,
								.max_iterations = 200,
								.chebyshev_rho = 0.0f,
								.chebyshev_delay = 5,
								.ground = -INFINITY };
}

void sere_vbd_destroy( sere_vbd* vbd )
{
	if ( vbd == NULL )
	{
		return;
	}
	void* const arrays[] = {
		vbd->block_row, vbd->slot_of,	  vbd->particle_of,	  vbd->neighbour,  vbd->spring,	 vbd->rest,
		vbd->stiffness, vbd->record,	  vbd->history[0],	  vbd->history[1], vbd->mass,	 vbd->tx,
		vbd->ty,		vbd->tz,		  vbd->push,		  vbd->a,		   vbd->b,		 vbd->offset,
		vbd->adjacency, vbd->spring_rest, vbd->spring_weight, vbd->results,	   vbd->barrier, vbd->cx,
		vbd->cy,		vbd->cz
	};
	sere_free_all( arrays, sizeof( arrays ) / sizeof( arrays[0] ) );
	free( vbd );
}

/* Each particle's springs, in spring order: offset[n + 1] and adjacency[2 m]. */
static sere_status build_adjacency( sere_vbd* v )
{
	const int32_t n = v->particle_count, m = v->spring_count;
	v->offset = sere_alloc( sizeof( int32_t ) * (size_t) ( n + 1 ) );
	v->adjacency = sere_alloc( sizeof( int32_t ) * (size_t) ( 2 * m + 1 ) );
	int32_t* fill = malloc( sizeof( int32_t ) * (size_t) ( n + 1 ) );
	if ( v->offset == NULL || v->adjacency == NULL || fill == NULL )
	{
		free( fill );
		return SERE_ERR_MEMORY;
	}
	for ( int32_t k = 0; k < m; ++k )
	{
		v->offset[v->a[k] + 1] += 1, v->offset[v->b[k] + 1] += 1;
	}
	for ( int32_t i = 0; i < n; ++i )
	{
		v->offset[i + 1] += v->offset[i];
	}
	memcpy( fill, v->offset, sizeof( int32_t ) * (size_t) n );
	for ( int32_t k = 0; k < m; ++k )
	{
		v->adjacency[fill[v->a[k]]++] = k, v->adjacency[fill[v->b[k]]++] = k;
	}
	free( fill );
	return SERE_OK;
}

/* Greedy coloring in particle index order, each particle the lowest color none of its
 * neighbours has; color[i] into color. */
static sere_status color_particles( const sere_vbd* v, int8_t* color, int32_t* colors )
{
	*colors = 0;
	for ( int32_t i = 0; i < v->particle_count; ++i )
	{
		uint64_t taken = 0;
		for ( int32_t e = v->offset[i]; e < v->offset[i + 1]; ++e )
		{
			const int32_t k = v->adjacency[e], o = v->a[k] == i ? v->b[k] : v->a[k];
			taken |= o < i ? UINT64_C( 1 ) << color[o] : 0;
		}
		if ( taken == UINT64_MAX )
		{
			return SERE_ERR_CAPACITY;
		}
		int c = __builtin_ctzll( ~taken );
		color[i] = (int8_t) c;
		*colors = c + 1 > *colors ? c + 1 : *colors;
	}
	return SERE_OK;
}

/* Particles sorted by (color, degree descending, index): the slots' order before padding. */
typedef struct particle_key
{
	int32_t color, degree, index;
} particle_key;

static int compare_keys( const void* lhs, const void* rhs )
{
	const particle_key *p = lhs, *q = rhs;
	if ( p->color != q->color )
	{
		return p->color < q->color ? -1 : 1;
	}
	if ( p->degree != q->degree )
	{
		return p->degree > q->degree ? -1 : 1;
	}
	return ( p->index > q->index ) - ( p->index < q->index );
}

/* Slots and blocks from the coloring: every color starts a new block, so a block holds one color
 * and starts on a cache line (SERE_LANES records of 16 bytes). */
static sere_status lay_out_slots( sere_vbd* v, const int8_t* color )
{
	const int32_t n = v->particle_count;
	particle_key* key = malloc( sizeof( particle_key ) * (size_t) ( n > 0 ? n : 1 ) );
	if ( key == NULL )
	{
		return SERE_ERR_MEMORY;
	}
	int32_t count[MAX_COLORS] = { 0 };
	for ( int32_t i = 0; i < n; ++i )
	{
		key[i] = ( particle_key ){ color[i], v->offset[i + 1] - v->offset[i], i };
		count[(int) color[i]] += 1;
	}
	qsort( key, (size_t) n, sizeof( particle_key ), compare_keys );
	v->blocks = 0;
	for ( int32_t c = 0; c < v->colors; ++c )
	{
		v->color_block[c] = v->blocks;
		v->blocks += ( count[c] + SERE_LANES - 1 ) / SERE_LANES;
	}
	v->color_block[v->colors] = v->blocks;
	v->slots = v->blocks * SERE_LANES;
	v->slot_of = sere_alloc( sizeof( int32_t ) * (size_t) ( n > 0 ? n : 1 ) );
	v->particle_of = sere_alloc( sizeof( int32_t ) * (size_t) ( v->slots + 1 ) );
	if ( v->slot_of == NULL || v->particle_of == NULL )
	{
		free( key );
		return SERE_ERR_MEMORY;
	}
	for ( int32_t s = 0; s < v->slots + 1; ++s )
	{
		v->particle_of[s] = -1;
	}
	for ( int32_t c = 0, k = 0; c < v->colors; ++c )
	{
		for ( int32_t j = 0; j < count[c]; ++j, ++k )
		{
			const int32_t s = v->color_block[c] * SERE_LANES + j;
			v->particle_of[s] = key[k].index;
			v->slot_of[key[k].index] = s;
		}
	}
	free( key );
	return SERE_OK;
}

/* The rows: block b has as many as its lanes' largest degree; lane j of row r holds the r-th
 * spring of the block's j-th particle, or padding. */
static sere_status lay_out_rows( sere_vbd* v )
{
	v->block_row = sere_alloc( sizeof( int32_t ) * (size_t) ( v->blocks + 1 ) );
	if ( v->block_row == NULL )
	{
		return SERE_ERR_MEMORY;
	}
	v->rows = 0;
	for ( int32_t block = 0; block < v->blocks; ++block )
	{
		int32_t degree = 0;
		for ( int32_t j = 0; j < SERE_LANES; ++j )
		{
			const int32_t p = v->particle_of[block * SERE_LANES + j];
			const int32_t d = p >= 0 ? v->offset[p + 1] - v->offset[p] : 0;
			degree = d > degree ? d : degree;
		}
		v->block_row[block] = v->rows;
		v->rows += degree;
	}
	v->block_row[v->blocks] = v->rows;
	const size_t entries = (size_t) v->rows * SERE_LANES + 1;
	v->neighbour = sere_alloc( sizeof( int32_t ) * entries );
	v->spring = sere_alloc( sizeof( int32_t ) * entries );
	float** const columns[] = { &v->rest, &v->stiffness };
	if ( v->neighbour == NULL || v->spring == NULL || !sere_alloc_floats( columns, 2, entries ) )
	{
		return SERE_ERR_MEMORY;
	}
	for ( int32_t block = 0; block < v->blocks; ++block )
	{
		for ( int32_t r = v->block_row[block]; r < v->block_row[block + 1]; ++r )
		{
			for ( int32_t j = 0; j < SERE_LANES; ++j )
			{
				const size_t e = (size_t) r * SERE_LANES + (size_t) j;
				const int32_t p = v->particle_of[block * SERE_LANES + j];
				const int32_t at = p >= 0 ? v->offset[p] + r - v->block_row[block] : -1;
				const int32_t k = p >= 0 && at < v->offset[p + 1] ? v->adjacency[at] : -1;
				const int32_t o = k < 0 ? -1 : v->a[k] == p ? v->b[k] : v->a[k];
				v->spring[e] = k < 0 ? v->spring_count : k;
				v->neighbour[e] = 4 * ( o < 0 ? v->slots : v->slot_of[o] );
			}
		}
	}
	return SERE_OK;
}

sere_status sere_vbd_create( const int32_t* a, const int32_t* b, int32_t spring_count, int32_t particle_count,
							 sere_vbd** out )
{
	if ( out == NULL || spring_count < 0 || particle_count < 0 || ( spring_count > 0 && ( a == NULL || b == NULL ) ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	*out = NULL;
	for ( int32_t k = 0; k < spring_count; ++k )
	{
		if ( a[k] < 0 || b[k] < 0 || a[k] >= particle_count || b[k] >= particle_count || a[k] == b[k] )
		{
			return SERE_ERR_ARGUMENT;
		}
	}
	sere_vbd* v = calloc( 1, sizeof( *v ) );
	if ( v == NULL )
	{
		return SERE_ERR_MEMORY;
	}
	v->particle_count = particle_count, v->spring_count = spring_count;
	v->a = sere_alloc( sizeof( int32_t ) * (size_t) ( spring_count + 1 ) );
	v->b = sere_alloc( sizeof( int32_t ) * (size_t) ( spring_count + 1 ) );
	float** const spring_columns[] = { &v->spring_rest, &v->spring_weight };
	int8_t* color = malloc( (size_t) particle_count + 1 );
	sere_status status = v->a != NULL && v->b != NULL && color != NULL &&
								 sere_alloc_floats( spring_columns, 2, (size_t) spring_count + 1 )
							 ? SERE_OK
							 : SERE_ERR_MEMORY;
	if ( status == SERE_OK )
	{
		memcpy( v->a, a, sizeof( int32_t ) * (size_t) spring_count );
		memcpy( v->b, b, sizeof( int32_t ) * (size_t) spring_count );
		for ( int32_t k = 0; k < spring_count; ++k )
		{
			v->spring_weight[k] = 1.0f;
		}
		v->spring_rest[spring_count] = 1.0f, v->spring_weight[spring_count] = INFINITY; /* padding */
		v->stiffness_stale = 1;
		status = build_adjacency( v );
	}
	status = status == SERE_OK ? color_particles( v, color, &v->colors ) : status;
	status = status == SERE_OK ? lay_out_slots( v, color ) : status;
	status = status == SERE_OK ? lay_out_rows( v ) : status;
	free( color );
	if ( status == SERE_OK )
	{
		const size_t records = 4 * (size_t) ( v->slots + 1 );
		float** const slot_columns[] = { &v->record, &v->history[0], &v->history[1] };
		float** const particle_columns[] = { &v->mass, &v->tx, &v->ty, &v->tz, &v->push, &v->cx, &v->cy, &v->cz };
		v->results = sere_alloc( sizeof( thread_slot ) * SERE_MAX_THREADS );
		v->barrier = sere_alloc( sizeof( sere_spin_barrier ) );
		if ( !sere_alloc_floats( slot_columns, 3, records ) ||
			 !sere_alloc_floats( particle_columns, 8, (size_t) v->slots + 1 ) || v->results == NULL ||
			 v->barrier == NULL )
		{
			status = SERE_ERR_MEMORY;
		}
	}
	if ( status != SERE_OK )
	{
		sere_vbd_destroy( v );
		return status;
	}
	*out = v;
	return SERE_OK;
}

sere_vbd_info sere_vbd_get_info( const sere_vbd* vbd )
{
	return ( sere_vbd_info ){ vbd->colors, vbd->blocks, vbd->rows * SERE_LANES, 2 * vbd->spring_count };
}

sere_status sere_vbd_set_rest( sere_vbd* vbd, const float* rest )
{
	if ( vbd == NULL || ( rest == NULL && vbd->spring_count > 0 ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	vbd->rest_valid = 0;
	/* every length looked at, without an early exit, so that the check runs in lanes (a frame
	 * sets every spring's) */
	int bad = 0;
	for ( int32_t k = 0; k < vbd->spring_count; ++k )
	{
		bad |= !( rest[k] > 0.0f ) | !( rest[k] <= FLT_MAX );
	}
	if ( bad )
	{
		return SERE_ERR_GEOMETRY;
	}
	memcpy( vbd->spring_rest, rest, sizeof( float ) * (size_t) vbd->spring_count );
	vbd->rest_valid = 1;
	vbd->rest_stale = 1; /* the next step's pack lays them out, in parallel */
	return SERE_OK;
}

sere_status sere_vbd_set_compliance_weights( sere_vbd* vbd, const float* weight )
{
	if ( vbd == NULL )
	{
		return SERE_ERR_ARGUMENT;
	}
	for ( int32_t k = 0; weight != NULL && k < vbd->spring_count; ++k )
	{
		if ( !( weight[k] > 0.0f ) || !isfinite( weight[k] ) )
		{
			return SERE_ERR_ARGUMENT;
		}
	}
	for ( int32_t k = 0; k < vbd->spring_count; ++k )
	{
		vbd->spring_weight[k] = weight != NULL ? weight[k] : 1.0f;
	}
	vbd->stiffness_stale = 1;
	return SERE_OK;
}

sere_status sere_vbd_set_threads( sere_vbd* vbd, int32_t threads )
{
	if ( vbd == NULL || !sere_threads_valid( threads ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	vbd->thread_count = threads;
	return SERE_OK;
}

static int params_valid( const sere_vbd_params* p )
{
	return p->dt > 0.0f && isfinite( p->dt ) && p->compliance > 0.0f && isfinite( p->compliance ) &&
		   p->tolerance > 0.0f && isfinite( p->tolerance ) && p->max_iterations >= 1 && p->chebyshev_rho >= 0.0f &&
		   p->chebyshev_rho < 1.0f && p->chebyshev_delay >= 2 && ( p->warm_start == 0 || p->warm_start == 1 ) &&
		   !isnan( p->ground ) && p->ground < INFINITY;
}

/* What a call asks of the sweeps. */
typedef struct step_setup
{
	float inverse_alpha; /* dt²/α: a spring's stiffness is this over its weight */
	float tolerance2;	 /* tolerance² (moves are compared squared) */
	float ground;
	float rho;
	int32_t delay, sweeps;
	int touch; /* the floor: loads and stores without the Newton step, `sweeps` sweeps */
	int warm;  /* start from the prediction plus the last step's correction */
} step_setup;

typedef struct step_outcome
{
	int32_t iterations, flags;
	float move2;
	int converged;
	float tolerance2; /* the stop the sweeps used: the caller's, or the positions' rounding */
} step_outcome;

/* A block's share of a sweep's work: its rows, and one row more for its own loads, 3 × 3 solve and
 * store. Each block's cycles over 100 Table 1 frames at 1 thread fit 1.3–1.4 rows a block on the
 * maple and the plane tree (0.5 on the wisteria); cut by this weight, the longer of two threads'
 * shares is 1.016 / 1.023 / 1.021 of half the sweep on the three leaves, against 1.043 / 1.040 /
 * 1.013 cut by rows alone. Blocks [0, b) of the whole sweep weigh this much. */
static int64_t blocks_weight( const sere_vbd* v, int32_t b )
{
	return (int64_t) v->block_row[b] + b;
}

/* The first block of color c whose weight before it (blocks_weight) is at least `weight`. */
static int32_t block_at_weight( const sere_vbd* v, int32_t c, int64_t weight )
{
	int32_t lo = v->color_block[c], hi = v->color_block[c + 1];
	while ( lo < hi )
	{
		const int32_t mid = lo + ( hi - lo ) / 2;
		if ( blocks_weight( v, mid ) < weight )
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

/* Thread t's blocks of color c, [*first, *last): equal shares of the color's weight, not of its
 * blocks, since a color's blocks are sorted by degree (an even cut of the blocks gave one thread
 * the triangle layer's twelve-spring particles and the other the Voronoi layer's six). */
static void color_share( const sere_vbd* v, int32_t c, int t, int threads, int32_t* first, int32_t* last )
{
	const int32_t b0 = v->color_block[c], b1 = v->color_block[c + 1];
	const int64_t begin = blocks_weight( v, b0 ), weight = blocks_weight( v, b1 ) - begin;
	*first = t == 0 ? b0 : block_at_weight( v, c, begin + weight * t / threads );
	*last = t + 1 == threads ? b1 : block_at_weight( v, c, begin + weight * ( t + 1 ) / threads );
}

/* Blocks [first, last)'s records, masses, prediction and the stiffnesses of their rows. Returns
 * the input's flags and raises *largest to the largest |coordinate|. */
static int32_t pack_blocks( sere_vbd* v, const float* px, const float* py, const float* pz, const float* inv_m,
							const step_setup* setup, int32_t first, int32_t last, float* largest )
{
	int32_t flags = 0;
	float big = *largest;
	for ( int32_t s = first * SERE_LANES; s < last * SERE_LANES; ++s )
	{
		const int32_t p = v->particle_of[s];
		float* r = v->record + 4 * (size_t) s;
		if ( p < 0 )
		{
			r[0] = r[1] = r[2] = r[3] = 0.0f;
			v->mass[s] = 1.0f, v->tx[s] = v->ty[s] = v->tz[s] = 0.0f;
			continue;
		}
		const float w = inv_m[p];
		flags |= isfinite( px[p] ) && isfinite( py[p] ) && isfinite( pz[p] ) && isfinite( w ) ? 0 : FLAG_NONFINITE;
		flags |= w < 0.0f ? FLAG_NEGATIVE_MASS : 0;
		r[0] = px[p], r[1] = py[p], r[2] = pz[p], r[3] = w > 0.0f ? 1.0f : 0.0f;
		if ( setup->warm && w > 0.0f )
		{
			/* the inertia's anchor stays the prediction; only where the sweeps begin moves, and
			 * never below the ground (a held particle stays where it is given, whatever it did
			 * when it was free) */
			const float z = r[2] + v->cz[s];
			r[0] += v->cx[s], r[1] += v->cy[s], r[2] = z < setup->ground ? setup->ground : z;
		}
		/* one instruction each (fmaxf is a library call); the new value first, so that a NaN
		 * (flagged above) is passed over as fmaxf passes it */
		big = sere_max_x86( fabsf( px[p] ), big );
		big = sere_max_x86( fabsf( py[p] ), big );
		big = sere_max_x86( fabsf( pz[p] ), big );
		/* a held particle's step is multiplied by 0; its mass only has to keep the block finite */
		v->mass[s] = w > 0.0f ? 1.0f / w : 1.0f;
		v->tx[s] = px[p], v->ty[s] = py[p], v->tz[s] = pz[p];
	}
	/* the rows take what changed since the last step (the padding's sentinel gives rest 1 and
	 * stiffness 0): branch-free gathers */
	const size_t begin = (size_t) v->block_row[first] * SERE_LANES, end = (size_t) v->block_row[last] * SERE_LANES;
	if ( v->rest_stale )
	{
		for ( size_t e = begin; e < end; ++e )
		{
			v->rest[e] = v->spring_rest[v->spring[e]];
		}
	}
	if ( v->stiffness_stale || v->inverse_alpha != setup->inverse_alpha )
	{
		for ( size_t e = begin; e < end; ++e )
		{
			v->stiffness[e] = setup->inverse_alpha / v->spring_weight[v->spring[e]];
		}
	}
	*largest = big;
	return flags;
}

/* Thread t's blocks, color by color as its sweeps take them (color_share), so that each block's
 * records and rows are written by the thread that sweeps and extrapolates them and stay in its
 * cache. Returns the input's flags. */
static int32_t pack( sere_vbd* v, const float* px, const float* py, const float* pz, const float* inv_m,
					 const step_setup* setup, int t, int threads, float* largest )
{
	int32_t flags = 0;
	*largest = 0.0f;
	for ( int32_t c = 0; c < v->colors; ++c )
	{
		int32_t first, last;
		color_share( v, c, t, threads, &first, &last );
		flags |= pack_blocks( v, px, py, pz, inv_m, setup, first, last, largest );
	}
	if ( t == 0 )
	{
		memset( v->record + 4 * (size_t) v->slots, 0, 4 * sizeof( float ) );
	}
	return flags;
}

/* The records of block b's lanes (a block's slots are consecutive). */
static float* block_records( const sere_vbd* v, int32_t block )
{
	return v->record + 4 * (size_t) block * SERE_LANES;
}

/* One Newton step on every lane of block b (module comment of sere_vbd_step); returns the
 * largest squared move, +∞ when a lane's is not finite. */
static float block_step( sere_vbd* v, int32_t block, const step_setup* setup )
{
	const int32_t s0 = block * SERE_LANES;
	sere_vf x, y, z, movable;
	sere_vf_load_block_records( block_records( v, block ), &x, &y, &z, &movable );
	const sere_vf m = sere_vf_load( v->mass + s0 );
	sere_vf gx = sere_vf_mul( m, sere_vf_sub( x, sere_vf_load( v->tx + s0 ) ) );
	sere_vf gy = sere_vf_mul( m, sere_vf_sub( y, sere_vf_load( v->ty + s0 ) ) );
	sere_vf gz = sere_vf_mul( m, sere_vf_sub( z, sere_vf_load( v->tz + s0 ) ) );
	/* the Hessian's off-diagonal and its anisotropic diagonal; the isotropic part Σ k β apart,
	 * added to the diagonal once after the rows */
	sere_vf hxx = m, hyy = m, hzz = m, hxy = sere_vf_splat( 0.0f ), hxz = hxy, hyz = hxy, isotropic = hxy;
	const sere_vf zero = hxy, one = sere_vf_splat( 1.0f ), tiny = sere_vf_splat( TINY_LENGTH );
	/* The rows in chunks, each in two passes: first every row's d and 1/|d| (the gather, then the
	 * √ and the division, the longest chain of a row), then the sums in row order. Back to back,
	 * the chains of many rows overlap in the out-of-order window. */
	for ( int32_t chunk = v->block_row[block]; chunk < v->block_row[block + 1]; chunk += CHUNK_ROWS )
	{
		const int32_t count =
			v->block_row[block + 1] - chunk < CHUNK_ROWS ? v->block_row[block + 1] - chunk : CHUNK_ROWS;
		sere_vf ends[CHUNK_ROWS][4];
		for ( int32_t q = 0; q < count; ++q )
		{
			sere_vf ox, oy, oz, ow;
			sere_vf_load_records_at( v->record, v->neighbour + (size_t) ( chunk + q ) * SERE_LANES, &ox, &oy, &oz,
									 &ow );
			const sere_vf dx = sere_vf_sub( x, ox ), dy = sere_vf_sub( y, oy ), dz = sere_vf_sub( z, oz );
			const sere_vf d2 = sere_vf_fma( dz, dz, sere_vf_fma( dy, dy, sere_vf_mul( dx, dx ) ) );
			ends[q][0] = dx, ends[q][1] = dy, ends[q][2] = dz;
			ends[q][3] = sere_vf_div( one, sere_vf_max( sere_vf_sqrt( d2 ), tiny ) );
		}
		for ( int32_t q = 0; q < count; ++q )
		{
			const size_t e = (size_t) ( chunk + q ) * SERE_LANES;
			const sere_vf k = sere_vf_load( v->stiffness + e ), l = sere_vf_load( v->rest + e );
			const sere_vf dx = ends[q][0], dy = ends[q][1], dz = ends[q][2], inverse = ends[q][3];
			/* Jeong Eq. 13's C = |d| − l and its force k C n = k (1 − l/|d|) d; the block
			 * k [(1 − β) n nᵀ + β I] with β = max(0, 1 − l/|d|), n nᵀ = d dᵀ/|d|², so that
			 * k β = max(0, force) (k ≥ 0); fused multiply-adds, one rounding each at every width */
			const sere_vf force = sere_vf_mul( k, sere_vf_fnma( l, inverse, one ) );
			gx = sere_vf_fma( force, dx, gx );
			gy = sere_vf_fma( force, dy, gy );
			gz = sere_vf_fma( force, dz, gz );
			const sere_vf across = sere_vf_max( zero, force );
			const sere_vf along = sere_vf_mul( sere_vf_sub( k, across ), sere_vf_mul( inverse, inverse ) );
			const sere_vf ax = sere_vf_mul( along, dx ), ay = sere_vf_mul( along, dy ), az = sere_vf_mul( along, dz );
			hxx = sere_vf_fma( ax, dx, hxx );
			hyy = sere_vf_fma( ay, dy, hyy );
			hzz = sere_vf_fma( az, dz, hzz );
			hxy = sere_vf_fma( ax, dy, hxy );
			hxz = sere_vf_fma( ax, dz, hxz );
			hyz = sere_vf_fma( ay, dz, hyz );
			isotropic = sere_vf_add( isotropic, across );
		}
	}
	hxx = sere_vf_add( hxx, isotropic ), hyy = sere_vf_add( hyy, isotropic ), hzz = sere_vf_add( hzz, isotropic );
	/* Δ = −H⁻¹ g by the adjugate of the symmetric block */
	const sere_vf c00 = sere_vf_sub( sere_vf_mul( hyy, hzz ), sere_vf_mul( hyz, hyz ) );
	const sere_vf c01 = sere_vf_sub( sere_vf_mul( hxz, hyz ), sere_vf_mul( hxy, hzz ) );
	const sere_vf c02 = sere_vf_sub( sere_vf_mul( hxy, hyz ), sere_vf_mul( hxz, hyy ) );
	const sere_vf c11 = sere_vf_sub( sere_vf_mul( hxx, hzz ), sere_vf_mul( hxz, hxz ) );
	const sere_vf c12 = sere_vf_sub( sere_vf_mul( hxy, hxz ), sere_vf_mul( hxx, hyz ) );
	const sere_vf c22 = sere_vf_sub( sere_vf_mul( hxx, hyy ), sere_vf_mul( hxy, hxy ) );
	const sere_vf det =
		sere_vf_add( sere_vf_add( sere_vf_mul( hxx, c00 ), sere_vf_mul( hxy, c01 ) ), sere_vf_mul( hxz, c02 ) );
	const sere_vf scale = sere_vf_div( movable, det ); /* held and padding lanes: 0 */
	const sere_vf sx =
		sere_vf_add( sere_vf_add( sere_vf_mul( c00, gx ), sere_vf_mul( c01, gy ) ), sere_vf_mul( c02, gz ) );
	const sere_vf sy =
		sere_vf_add( sere_vf_add( sere_vf_mul( c01, gx ), sere_vf_mul( c11, gy ) ), sere_vf_mul( c12, gz ) );
	const sere_vf sz =
		sere_vf_add( sere_vf_add( sere_vf_mul( c02, gx ), sere_vf_mul( c12, gy ) ), sere_vf_mul( c22, gz ) );
	const sere_vf mx = sere_vf_mul( sx, scale ), my = sere_vf_mul( sy, scale );
	sere_vf nz = sere_vf_sub( z, sere_vf_mul( sz, scale ) );
	/* the ground as a bound: a step that ends below it ends on it; where it did, the bound's
	 * reaction, ∂E/∂z at the start of the step over the mass, is the displacement the ground
	 * holds the particle by (the caller's friction, vbd.h) */
	const sere_vf depth =
		sere_vf_mul( movable, sere_vf_max( zero, sere_vf_sub( sere_vf_splat( setup->ground ), nz ) ) );
	nz = sere_vf_add( nz, depth );
	const sere_vf mz = sere_vf_sub( nz, z );
	const sere_vf reaction = sere_vf_div( sere_vf_max( zero, gz ), m );
	sere_vf_store( v->push + s0, sere_vf_keep( sere_vf_gt( depth, zero ), reaction ) );
	sere_vf_store_block_records( block_records( v, block ), sere_vf_sub( x, mx ), sere_vf_sub( y, my ), nz, movable );
	const sere_vf move2 =
		sere_vf_add( sere_vf_add( sere_vf_mul( mx, mx ), sere_vf_mul( my, my ) ), sere_vf_mul( mz, mz ) );
	return sere_vmask_any( sere_vf_not_le( move2, sere_vf_splat( FLT_MAX ) ) ) ? INFINITY : sere_vf_max_all( move2 );
}

/* block_step's loads and stores with a sum in place of the step: the records go back unchanged
 * and the sum into push, so no load can be left out. */
static float block_touch( sere_vbd* v, int32_t block )
{
	const int32_t s0 = block * SERE_LANES;
	sere_vf x, y, z, movable;
	sere_vf_load_block_records( block_records( v, block ), &x, &y, &z, &movable );
	sere_vf sum = sere_vf_add( sere_vf_load( v->mass + s0 ), sere_vf_load( v->tx + s0 ) );
	sum = sere_vf_add( sum, sere_vf_add( sere_vf_load( v->ty + s0 ), sere_vf_load( v->tz + s0 ) ) );
	for ( int32_t r = v->block_row[block]; r < v->block_row[block + 1]; ++r )
	{
		const size_t e = (size_t) r * SERE_LANES;
		sere_vf ox, oy, oz, ow;
		sere_vf_load_records_at( v->record, v->neighbour + e, &ox, &oy, &oz, &ow );
		sum = sere_vf_add( sum, sere_vf_add( sere_vf_add( ox, oy ), oz ) );
		sum = sere_vf_add( sum, sere_vf_add( sere_vf_load( v->stiffness + e ), sere_vf_load( v->rest + e ) ) );
	}
	sere_vf_store( v->push + s0, sum );
	sere_vf_store_block_records( block_records( v, block ), x, y, z, movable );
	return 0.0f;
}

/* Publishes thread t's largest squared move (or any non-negative value) and flags of the sweep and
 * returns the team's largest (every thread reads all slots after the barrier, so all decide
 * alike). */
static float exchange( sere_vbd* v, int t, int threads, int parity, float move2, int32_t* flags )
{
	v->results[t].move2[parity] = move2;
	v->results[t].flags[parity] = *flags;
	sere_spin_barrier_wait( v->barrier, threads );
	float worst = 0.0f;
	int32_t all = 0;
	for ( int u = 0; u < threads; ++u )
	{
		worst = v->results[u].move2[parity] > worst ? v->results[u].move2[parity] : worst;
		all |= v->results[u].flags[parity];
	}
	*flags = all;
	return worst;
}

/* Chebyshev semi-iteration after sweep k (vbd.h) over the blocks thread t swept, with its view
 * of the history: hist[1] holds x_{k−1} and hist[0] x_{k−2}. x_k is written to the records and
 * over x_{k−2}, which then becomes the newest; ω = 0 (within the delay) only records x̂_k. Each
 * thread keeps the history of its own blocks, so no other thread reads it. The movable flag of a
 * record comes out as it went in (ω (f − f) + f = f). The ground is left to the next sweep, whose
 * every step ends above it: the positions returned are a sweep's, never an extrapolation's. */
static void chebyshev( sere_vbd* v, float omega, float** hist, int t, int threads )
{
	float* restrict x = v->record;
	float* restrict old = hist[0];
	for ( int32_t c = 0; c < v->colors; ++c )
	{
		int32_t first, last;
		color_share( v, c, t, threads, &first, &last );
		const size_t begin = 4 * (size_t) first * SERE_LANES, end = 4 * (size_t) last * SERE_LANES;
		if ( omega == 0.0f )
		{
			memcpy( old + begin, x + begin, sizeof( float ) * ( end - begin ) );
		}
		for ( size_t i = begin; omega != 0.0f && i < end; ++i )
		{
			const float r = omega * ( x[i] - old[i] ) + old[i];
			x[i] = r;
			old[i] = r;
		}
	}
	hist[0] = hist[1];
	hist[1] = old;
}

/* The colored sweeps of thread t; every thread runs the same control flow. */
static step_outcome sweep( sere_vbd* v, const step_setup* setup, float tolerance2, int32_t flags, int t, int threads )
{
	step_outcome result = { 0, flags, 0.0f, 0, tolerance2 };
	float omega = 0.0f;
	int parity = 0;
	float* hist[2] = { v->history[0], v->history[1] };
	if ( setup->rho > 0.0f )
	{
		chebyshev( v, 0.0f, hist, t, threads ); /* x_0, the prediction */
	}
	for ( int32_t k = 1; k <= setup->sweeps && result.flags == 0; ++k )
	{
		float worst = 0.0f;
		for ( int32_t c = 0; c < v->colors; ++c )
		{
			int32_t first, last;
			color_share( v, c, t, threads, &first, &last );
			for ( int32_t block = first; block < last; ++block )
			{
				const float move2 = setup->touch ? block_touch( v, block ) : block_step( v, block, setup );
				worst = move2 > worst ? move2 : worst;
			}
			if ( c + 1 < v->colors )
			{
				sere_spin_barrier_wait( v->barrier, threads );
			}
		}
		int32_t sweep_flags = worst == INFINITY ? FLAG_NONFINITE : 0;
		result.move2 = exchange( v, t, threads, parity, worst, &sweep_flags );
		result.flags |= sweep_flags;
		result.iterations = k;
		parity ^= 1;
		if ( result.flags != 0 || ( !setup->touch && result.move2 <= tolerance2 ) )
		{
			result.converged = result.flags == 0;
			break;
		}
		if ( setup->rho > 0.0f && k < setup->sweeps )
		{
			const float rho2 = setup->rho * setup->rho;
			omega = k <= setup->delay		? 0.0f
					: k == setup->delay + 1 ? 2.0f / ( 2.0f - rho2 )
											: 4.0f / ( 4.0f - rho2 * omega );
			chebyshev( v, omega, hist, t, threads );
			sere_spin_barrier_wait( v->barrier, threads );
		}
	}
	return result;
}

static step_outcome run( sere_vbd* v, float* px, float* py, float* pz, const float* inv_m, const step_setup* setup )
{
	int requested = sere_team_for( v->thread_count );
	requested = requested < 1 ? 1 : requested > SERE_MAX_THREADS ? SERE_MAX_THREADS : requested;
	requested = sere_tuner_team( &v->tuner, requested );
	step_outcome outcome = { 0, 0, 0.0f, 0, 0.0f };
	int team = requested;
	double seconds = 0.0;
	/* pack reads the stale flags in every thread; they are cleared once the region has ended */
#pragma omp parallel num_threads( requested )
	{
		const int t = omp_get_thread_num(), threads = omp_get_num_threads();
		float largest;
		int32_t flags = pack( v, px, py, pz, inv_m, setup, t, threads, &largest );
		/* parity 1: the sweeps start on parity 0, and a slot's two halves are never read together */
		largest = exchange( v, t, threads, 1, largest, &flags );
		/* no sweep can move a particle by less than its coordinates' rounding: a tolerance below
		 * it would only run to the cap */
		const float rounding = FLT_EPSILON * largest;
		const float tolerance2 = fmaxf( setup->tolerance2, rounding * rounding );
		const double start = omp_get_wtime();
		step_outcome result = sweep( v, setup, tolerance2, flags, t, threads );
		const double swept = omp_get_wtime() - start;
		if ( result.flags == 0 && !setup->touch )
		{
			for ( int32_t c = 0; c < v->colors; ++c )
			{
				int32_t first, last;
				color_share( v, c, t, threads, &first, &last );
				for ( int32_t s = first * SERE_LANES; s < last * SERE_LANES; ++s )
				{
					const float* r = v->record + 4 * (size_t) s;
					v->cx[s] = r[0] - v->tx[s], v->cy[s] = r[1] - v->ty[s], v->cz[s] = r[2] - v->tz[s];
				}
			}
			int32_t first, last;
			sere_team_share( 0, v->particle_count, t, threads, &first, &last );
			for ( int32_t p = first; p < last; ++p )
			{
				const float* r = v->record + 4 * (size_t) v->slot_of[p];
				px[p] = r[0], py[p] = r[1], pz[p] = r[2];
			}
		}
		if ( t == 0 )
		{
			outcome = result;
			team = threads, seconds = swept;
		}
	}
	/* the floor's sweeps run the step's choice but are no measure of it: theirs are faster */
	if ( !setup->touch )
	{
		sere_tuner_record( &v->tuner, team, seconds, outcome.iterations );
	}
	v->rest_stale = v->stiffness_stale = 0;
	v->inverse_alpha = setup->inverse_alpha;
	/* a refused step leaves the last correction as it was */
	v->correction_valid |= !setup->touch && outcome.flags == 0;
	return outcome;
}

sere_status sere_vbd_step( sere_vbd* vbd, float* px, float* py, float* pz, const float* inv_m,
						   const sere_vbd_params* params, sere_vbd_report* report )
{
	if ( report != NULL )
	{
		memset( report, 0, sizeof( *report ) );
	}
	if ( vbd == NULL || params == NULL || report == NULL ||
		 ( vbd->particle_count > 0 && ( px == NULL || py == NULL || pz == NULL || inv_m == NULL ) ) ||
		 !params_valid( params ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	vbd->push_valid = 0;
	if ( !vbd->rest_valid )
	{
		return SERE_ERR_GEOMETRY;
	}
	const double dt = params->dt;
	const step_setup setup = { (float) ( dt * dt / params->compliance ),
							   params->tolerance * params->tolerance,
							   params->ground,
							   params->chebyshev_rho,
							   params->chebyshev_delay,
							   params->max_iterations,
							   0,
							   params->warm_start && vbd->correction_valid };
	const step_outcome outcome = run( vbd, px, py, pz, inv_m, &setup );
	if ( outcome.flags & FLAG_NEGATIVE_MASS )
	{
		return SERE_ERR_ARGUMENT;
	}
	if ( outcome.flags & FLAG_NONFINITE )
	{
		return SERE_ERR_NONFINITE;
	}
	vbd->push_valid = 1;
	report->iterations = outcome.iterations;
	report->max_move = sqrtf( outcome.move2 );
	report->tolerance = sqrtf( outcome.tolerance2 );
	report->hit_cap = !outcome.converged;
	return SERE_OK;
}

sere_status sere_vbd_ground_push( const sere_vbd* vbd, float* push )
{
	if ( vbd == NULL || ( push == NULL && vbd->particle_count > 0 ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	for ( int32_t p = 0; vbd->push_valid && p < vbd->particle_count; ++p )
	{
		push[p] += vbd->push[vbd->slot_of[p]];
	}
	return SERE_OK;
}

sere_status sere_vbd_step_residual( const sere_vbd* vbd, const float* px, const float* py, const float* pz,
									const float* tx, const float* ty, const float* tz, const float* inv_m,
									const sere_vbd_params* params, sere_vbd_residuals* out )
{
	if ( vbd == NULL || px == NULL || py == NULL || pz == NULL || tx == NULL || ty == NULL || tz == NULL ||
		 inv_m == NULL || params == NULL || out == NULL || !params_valid( params ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	if ( !vbd->rest_valid )
	{
		return SERE_ERR_GEOMETRY;
	}
	const double inverse_alpha = (double) params->dt * params->dt / params->compliance;
	double primal = 0.0, inertia = 0.0, constraint = 0.0;
	int32_t counted = 0;
	for ( int32_t i = 0; i < vbd->particle_count; ++i )
	{
		if ( !( inv_m[i] > 0.0f ) || pz[i] <= params->ground )
		{
			continue;
		}
		const double m = 1.0 / inv_m[i];
		const double g[3] = { m * ( (double) px[i] - tx[i] ), m * ( (double) py[i] - ty[i] ),
							  m * ( (double) pz[i] - tz[i] ) };
		double f[3] = { 0.0, 0.0, 0.0 };
		for ( int32_t e = vbd->offset[i]; e < vbd->offset[i + 1]; ++e )
		{
			const int32_t k = vbd->adjacency[e], o = vbd->a[k] == i ? vbd->b[k] : vbd->a[k];
			const double d[3] = { (double) px[i] - px[o], (double) py[i] - py[o], (double) pz[i] - pz[o] };
			const double length = sqrt( d[0] * d[0] + d[1] * d[1] + d[2] * d[2] );
			const double force =
				length > 0.0 ? inverse_alpha / vbd->spring_weight[k] * ( length - vbd->spring_rest[k] ) / length : 0.0;
			f[0] += force * d[0], f[1] += force * d[1], f[2] += force * d[2];
		}
		for ( int r = 0; r < 3; ++r )
		{
			primal += ( g[r] + f[r] ) * ( g[r] + f[r] );
			inertia += g[r] * g[r];
			constraint += f[r] * f[r];
		}
		counted += 1;
	}
	*out = ( sere_vbd_residuals ){ sqrt( primal ), sqrt( inertia ), sqrt( constraint ), counted };
	return SERE_OK;
}

sere_status sere_vbd_touch_sweeps( sere_vbd* vbd, float* px, float* py, float* pz, const float* inv_m, int32_t sweeps )
{
	if ( vbd == NULL || sweeps < 1 || ( vbd->particle_count > 0 && ( px == NULL || py == NULL || pz == NULL ) ) ||
		 ( vbd->particle_count > 0 && inv_m == NULL ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	const step_setup setup = { 1.0f, 0.0f, -INFINITY, 0.0f, 2, sweeps, 1, 0 };
	const step_outcome outcome = run( vbd, px, py, pz, inv_m, &setup );
	vbd->push_valid = 0;
	return outcome.flags & FLAG_NEGATIVE_MASS ? SERE_ERR_ARGUMENT : outcome.flags != 0 ? SERE_ERR_NONFINITE : SERE_OK;
}
