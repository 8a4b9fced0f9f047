/* _GNU_SOURCE: sched_getaffinity for internal/team.h. */
#define _GNU_SOURCE

#include "solve/cg.h"
#include "core/internal/team.h"

#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

enum
{
	LANES = SERE_SELL_C,
	CHUNKS_PER_BLOCK = SERE_CG_BLOCK / SERE_SELL_C
};

static inline double row_dot( const sere_csr* a, int32_t i, const double* x )
{
	double sum = 0.0;
	for ( int32_t k = a->row_ptr[i]; k < a->row_ptr[i + 1]; ++k )
	{
		sum += a->val[k] * x[a->col[k]];
	}
	return sum;
}

void sere_csr_spmv( const sere_csr* a, const double* x, double* y )
{
#pragma omp parallel for num_threads( sere_team_default() ) schedule( static )
	for ( int32_t i = 0; i < a->rows; ++i )
	{
		y[i] = row_dot( a, i, x );
	}
}

void sere_sell_destroy( sere_sell* s )
{
	if ( s == NULL )
	{
		return;
	}
	sere_free( s->chunk_ptr );
	sere_free( s->row );
	sere_free( s->col );
	sere_free( s->val );
	sere_free( s->slot );
	sere_free( s->local_col );
	sere_free( s->diagonal );
	free( s );
}

typedef struct row_length
{
	int32_t row, length;
} row_length;

/* Longest first; ties keep row order, so the order is total and rows stay near their neighbours. */
static int by_length( const void* left, const void* right )
{
	const row_length *l = left, *r = right;
	if ( l->length != r->length )
	{
		return l->length > r->length ? -1 : 1;
	}
	return l->row < r->row ? -1 : l->row > r->row;
}

/* The CG step length α = γ / pᵀAp, or why there is none: a non-finite γ or pᵀAp
 * (SERE_ERR_NONFINITE), or pᵀAp ≤ 0, a matrix that is not SPD (SERE_ERR_NOT_SPD). */
static sere_status cg_step_length( double pap, double gamma, double* alpha )
{
	if ( !isfinite( pap ) || !isfinite( gamma ) )
	{
		return SERE_ERR_NONFINITE;
	}
	if ( !( pap > 0.0 ) )
	{
		return SERE_ERR_NOT_SPD;
	}
	*alpha = gamma / pap;
	return SERE_OK;
}

/* Row pointers that never decrease and column indices inside the matrix (the caller has checked
 * row_ptr[0] = 0 and row_ptr[rows] = nnz). */
static int csr_indices_valid( const sere_csr* a )
{
	for ( int32_t i = 0; i < a->rows; ++i )
	{
		if ( a->row_ptr[i + 1] < a->row_ptr[i] )
		{
			return 0;
		}
	}
	for ( int32_t k = 0; k < a->nnz; ++k )
	{
		if ( a->col[k] < 0 || a->col[k] >= a->rows )
		{
			return 0;
		}
	}
	return 1;
}

sere_status sere_sell_create( const sere_csr* a, int32_t sigma, sere_sell** out )
{
	if ( a == NULL || out == NULL || a->rows <= 0 || a->nnz < 0 || a->row_ptr == NULL || sigma < LANES ||
		 sigma % LANES != 0 || SERE_CG_BLOCK % sigma != 0 || a->row_ptr[0] != 0 || a->row_ptr[a->rows] != a->nnz )
	{
		return SERE_ERR_ARGUMENT;
	}
	const int32_t n = a->rows;
	if ( !csr_indices_valid( a ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	sere_sell* s = calloc( 1, sizeof( *s ) );
	row_length* order = malloc( sizeof( row_length ) * (size_t) n );
	if ( s == NULL || order == NULL )
	{
		free( s );
		free( order );
		return SERE_ERR_MEMORY;
	}
	s->rows = n;
	s->nnz = a->nnz;
	s->sigma = sigma;
	s->chunks = ( n + LANES - 1 ) / LANES;
	for ( int32_t i = 0; i < n; ++i )
	{
		order[i] = ( row_length ){ i, a->row_ptr[i + 1] - a->row_ptr[i] };
	}
	for ( int32_t start = 0; start < n; start += sigma )
	{
		int32_t count = n - start < sigma ? n - start : sigma;
		qsort( order + start, (size_t) count, sizeof( row_length ), by_length );
	}
	s->chunk_ptr = sere_alloc( sizeof( int32_t ) * ( (size_t) s->chunks + 1 ) );
	s->row = sere_alloc( sizeof( int32_t ) * (size_t) s->chunks * LANES );
	if ( s->chunk_ptr == NULL || s->row == NULL )
	{
		free( order );
		sere_sell_destroy( s );
		return SERE_ERR_MEMORY;
	}
	int64_t slots = 0;
	for ( int32_t c = 0; c < s->chunks; ++c )
	{
		int32_t width = 0;
		for ( int32_t l = 0; l < LANES; ++l )
		{
			int32_t i = c * LANES + l;
			s->row[c * LANES + l] = i < n ? order[i].row : -1;
			width = i < n && order[i].length > width ? order[i].length : width;
		}
		slots += (int64_t) width * LANES;
		if ( slots > INT32_MAX )
		{
			free( order );
			sere_sell_destroy( s );
			return SERE_ERR_ARGUMENT;
		}
		s->chunk_ptr[c + 1] = (int32_t) slots;
	}
	free( order );
	/* At least one slot, so an all-empty matrix still has arrays to point at. */
	size_t stored = slots > 0 ? (size_t) slots : 1;
	s->col = sere_alloc( sizeof( int32_t ) * stored );
	s->val = sere_alloc( sizeof( double ) * stored );
	s->slot = sere_alloc( sizeof( int32_t ) * ( a->nnz > 0 ? (size_t) a->nnz : 1 ) );
	s->local_col = sere_alloc( sizeof( int32_t ) * stored );
	s->diagonal = sere_alloc( sizeof( int32_t ) * (size_t) s->chunks * LANES );
	int32_t* position = malloc( sizeof( int32_t ) * (size_t) n );
	if ( s->col == NULL || s->val == NULL || s->slot == NULL || s->local_col == NULL || s->diagonal == NULL ||
		 position == NULL )
	{
		free( position );
		sere_sell_destroy( s );
		return SERE_ERR_MEMORY;
	}
	for ( int32_t at = 0; at < s->chunks * LANES; ++at )
	{
		if ( s->row[at] >= 0 )
		{
			position[s->row[at]] = at;
		}
	}
	for ( int32_t c = 0; c < s->chunks; ++c )
	{
		int32_t width = ( s->chunk_ptr[c + 1] - s->chunk_ptr[c] ) / LANES;
		for ( int32_t l = 0; l < LANES; ++l )
		{
			int32_t i = s->row[c * LANES + l];
			int32_t begin = i >= 0 ? a->row_ptr[i] : 0, length = i >= 0 ? a->row_ptr[i + 1] - begin : 0;
			/* Padding repeats the row's last column: x_j is read anyway, so padding touches no
			 * new cache line and meets a non-finite x_j only where the row itself does. */
			int32_t pad = length > 0 ? a->col[begin + length - 1] : ( i >= 0 ? i : 0 );
			for ( int32_t k = 0; k < width; ++k )
			{
				int32_t at = s->chunk_ptr[c] + k * LANES + l;
				s->col[at] = k < length ? a->col[begin + k] : pad;
				s->local_col[at] = position[s->col[at]];
				s->val[at] = k < length ? a->val[begin + k] : 0.0;
				if ( k < length )
				{
					s->slot[begin + k] = at;
				}
			}
			int32_t* diagonal = s->diagonal + c * LANES + l;
			*diagonal = -1;
			for ( int32_t k = 0; k < length; ++k )
			{
				if ( a->col[begin + k] != i )
				{
					continue;
				}
				if ( *diagonal >= 0 )
				{
					free( position );
					sere_sell_destroy( s );
					return SERE_ERR_ARGUMENT;
				}
				*diagonal = s->chunk_ptr[c] + k * LANES + l;
			}
		}
	}
	free( position );
	*out = s;
	return SERE_OK;
}

sere_status sere_sell_update( sere_sell* s, const sere_csr* a )
{
	if ( s == NULL || a == NULL || a->rows != s->rows || a->nnz != s->nnz )
	{
		return SERE_ERR_ARGUMENT;
	}
	int mismatch = 0;
#pragma omp parallel for num_threads( sere_team_default() ) schedule( static ) reduction( | : mismatch )
	for ( int32_t k = 0; k < a->nnz; ++k )
	{
		s->val[s->slot[k]] = a->val[k];
		mismatch |= s->col[s->slot[k]] != a->col[k];
	}
	return mismatch ? SERE_ERR_ARGUMENT : SERE_OK;
}

/* A chunk's sums live in two 4-lane vectors (a vector type, not a double[8]: gcc keeps an
 * array in memory, and every step of the sums then waits on a store and a reload; 4 lanes, one
 * AVX2 register, because gcc lowers wider vector types through memory where they are not
 * native). Values pass through pointers so that no vector crosses a call ABI. */
typedef double half_t __attribute__( ( vector_size( 4 * sizeof( double ) ) ) );
_Static_assert( SERE_SELL_C == 8, "a chunk is two 4-lane vectors" );

typedef struct lanes_t
{
	half_t lo, hi;
} lanes_t;

/* A chunk's 8 lanes of a position-indexed vector (sere_alloc aligns to SERE_ALIGN, chunks start
 * at multiples of 8 doubles): direct vector loads and stores, no copy through the stack. */
static inline lanes_t load_lanes( const double* v )
{
	return ( lanes_t ){ *(const half_t*) v, *(const half_t*) ( v + 4 ) };
}

static inline void store_lanes( double* v, const lanes_t* in )
{
	*(half_t*) v = in->lo;
	*(half_t*) ( v + 4 ) = in->hi;
}

static inline void gather( half_t* out, const double* x, const int32_t* col )
{
	*out = ( half_t ){ x[col[0]], x[col[1]], x[col[2]], x[col[3]] };
}

/* Rows of chunk c times x, entries in CSR order; col is the layout's col (x indexed by row) or
 * local_col (x indexed by position). */
static inline void chunk_product( const sere_sell* a, const int32_t* col, int32_t c, const double* x, lanes_t* out )
{
	half_t lo = { 0.0 }, hi = { 0.0 }, xlo, xhi;
	for ( int32_t s = a->chunk_ptr[c]; s < a->chunk_ptr[c + 1]; s += LANES )
	{
		gather( &xlo, x, col + s );
		gather( &xhi, x, col + s + 4 );
		lo += *(const half_t*) ( a->val + s ) * xlo;
		hi += *(const half_t*) ( a->val + s + 4 ) * xhi;
	}
	out->lo = lo;
	out->hi = hi;
}

/* Lane l of a chunk's sums. */
static inline double lane( const lanes_t* sum, int32_t l )
{
	return l < 4 ? sum->lo[l] : sum->hi[l - 4];
}

static inline int32_t chunk_lanes( const sere_sell* a, int32_t c )
{
	return a->rows - c * LANES < LANES ? a->rows - c * LANES : LANES;
}

void sere_sell_spmv( const sere_sell* a, const double* x, double* y )
{
#pragma omp parallel for num_threads( sere_team_default() ) schedule( static )
	for ( int32_t c = 0; c < a->chunks; ++c )
	{
		lanes_t sum;
		chunk_product( a, a->col, c, x, &sum );
		for ( int32_t l = 0; l < chunk_lanes( a, c ); ++l )
		{
			y[a->row[c * LANES + l]] = lane( &sum, l );
		}
	}
}

/* Vectors of the solve, indexed by position (see sere_sell): x and b as permuted in. */
struct sere_cg_workspace
{
	int32_t capacity;
	int32_t positions; /* vector length: n rounded to chunks, plus a chunk of padding per SGS color */
	int32_t block_capacity;
	double *x, *b, *r, *u, *w, *p, *s, *inv_diag, *t, *z;
	double* partial;	 /* 4 sums per block: rᵀr, uᵀw, rᵀu, bᵀb */
	double* chunk_delta; /* SGS: per chunk, its share of uᵀw */
};

sere_status sere_cg_create( int32_t n, sere_cg_workspace** out )
{
	if ( n <= 0 || out == NULL )
	{
		return SERE_ERR_ARGUMENT;
	}
	sere_cg_workspace* w = calloc( 1, sizeof( *w ) );
	if ( w == NULL )
	{
		return SERE_ERR_MEMORY;
	}
	/* SELL positions run to ⌈n / SERE_SELL_C⌉ · SERE_SELL_C ≤ sere_pad( n ); SGS positions pad
	 * each color to whole chunks, at most one chunk more per color. */
	_Static_assert( SERE_PAD % SERE_SELL_C == 0, "padding covers the last chunk" );
	if ( n > INT32_MAX - SERE_PAD - SERE_SELL_C * SERE_SGS_MAX_COLORS )
	{
		free( w );
		return SERE_ERR_ARGUMENT;
	}
	w->positions = sere_pad( n ) + SERE_SELL_C * SERE_SGS_MAX_COLORS;
	size_t bytes = sizeof( double ) * (size_t) w->positions;
	w->capacity = n;
	w->block_capacity = ( w->positions + SERE_CG_BLOCK - 1 ) / SERE_CG_BLOCK;
	double** vectors[] = { &w->x, &w->b, &w->r, &w->u, &w->w, &w->p, &w->s, &w->inv_diag, &w->t, &w->z };
	int failed = 0;
	for ( size_t k = 0; k < sizeof( vectors ) / sizeof( vectors[0] ); ++k )
	{
		*vectors[k] = sere_alloc( bytes );
		failed |= *vectors[k] == NULL;
	}
	w->partial = sere_alloc( sizeof( double ) * 4 * (size_t) w->block_capacity );
	w->chunk_delta = sere_alloc( sizeof( double ) * (size_t) ( w->positions / SERE_SELL_C ) );
	if ( failed || w->partial == NULL || w->chunk_delta == NULL )
	{
		sere_cg_destroy( w );
		return SERE_ERR_MEMORY;
	}
	*out = w;
	return SERE_OK;
}

void sere_cg_destroy( sere_cg_workspace* w )
{
	if ( w == NULL )
	{
		return;
	}
	double* vectors[] = { w->x, w->b, w->r, w->u, w->w, w->p, w->s, w->inv_diag, w->t, w->z };
	for ( size_t k = 0; k < sizeof( vectors ) / sizeof( vectors[0] ); ++k )
	{
		sere_free( vectors[k] );
	}
	sere_free( w->partial );
	sere_free( w->chunk_delta );
	free( w );
}

/* Sum of partial[slot], partial[slot + 4], ... over blocks in block order. */
static double block_sum( const double* partial, int32_t blocks, int slot )
{
	double sum = 0.0;
	for ( int32_t k = 0; k < blocks; ++k )
	{
		sum += partial[4 * k + slot];
	}
	return sum;
}

static inline int32_t block_end( int32_t blk, int32_t n )
{
	return ( blk + 1 ) * SERE_CG_BLOCK < n ? ( blk + 1 ) * SERE_CG_BLOCK : n;
}

/* y = A v for block blk's positions, each chunk one contiguous store. */
static inline void block_product( const sere_sell* a, int32_t blk, const double* v, double* y )
{
	int32_t chunk_end = ( blk + 1 ) * CHUNKS_PER_BLOCK < a->chunks ? ( blk + 1 ) * CHUNKS_PER_BLOCK : a->chunks;
	for ( int32_t c = blk * CHUNKS_PER_BLOCK; c < chunk_end; ++c )
	{
		lanes_t sum;
		chunk_product( a, a->local_col, c, v, &sum );
		store_lanes( y + c * LANES, &sum );
	}
}

/* w = Au for block blk, then its partial sums of δ = uᵀw (slot 1) and γ = rᵀu (slot 2). */
static inline void block_product_sums( const sere_sell* a, int32_t blk, int32_t np, const double* u, const double* r,
									   double* w, double* partial )
{
	block_product( a, blk, u, w );
	double delta = 0.0, gamma = 0.0;
	/* Vector partial sums: the block, not the thread, decides how the sum is split, so every
	 * thread count gets the same bits (and 1 thread runs faster than the serial chain of
	 * dependent adds that -ffp-contract=off and no -ffast-math would otherwise leave). */
#pragma omp simd reduction( + : delta, gamma )
	for ( int32_t i = blk * SERE_CG_BLOCK; i < block_end( blk, np ); ++i )
	{
		delta += u[i] * w[i];
		gamma += r[i] * u[i];
	}
	partial[4 * blk + 1] = delta;
	partial[4 * blk + 2] = gamma;
}

sere_status sere_cg_solve( sere_cg_workspace* ws, const sere_sell* a, const double* b_in, double* x_in,
						   double tolerance, int32_t max_iterations, sere_cg_result* result )
{
	result->iterations = 0;
	result->residual = 0.0;
	if ( ws == NULL || a == NULL || b_in == NULL || x_in == NULL || a->rows <= 0 || a->rows > ws->capacity ||
		 a->sigma <= 0 || SERE_CG_BLOCK % a->sigma != 0 || !( tolerance >= 0.0 ) || max_iterations < 0 )
	{
		return SERE_ERR_ARGUMENT;
	}
	const int32_t np = a->chunks * LANES; /* positions, the last chunk's padding lanes included */
	const int32_t blocks = ( np + SERE_CG_BLOCK - 1 ) / SERE_CG_BLOCK;
	double *x = ws->x, *b = ws->b, *r = ws->r, *u = ws->u, *w = ws->w, *p = ws->p, *s = ws->s;
	double *inv_diag = ws->inv_diag, *partial = ws->partial;
	sere_status status = SERE_OK;
	int32_t iterations = 0;
	double relative = 0.0;
	int bad_diagonal = 0, nonfinite = 0;

	/* Parallel regions that span many steps: the systems are small (thousands of rows), so
	 * fork/join per kernel would cost more than the kernels. Every thread takes the same
	 * decisions from the same block sums, so no broadcast is needed. Blocks are whole chunks
	 * (σ divides SERE_CG_BLOCK), so a block's products are written and read by one thread.
	 *
	 * The recurrence is Chronopoulos and Gear's (1989) form of Jacobi PCG: besides x, r and
	 * u = D⁻¹r it carries w = Au and s = Ap, updated as s = w + βs, so the one product per
	 * iteration is w = Au, and both sums it needs, δ = uᵀw and γ = rᵀu, come out of that same
	 * sweep; pᵀAp = δ − βγ/α_prev follows from them. An iteration is then two sweeps and two
	 * barriers (the product needs every block's u; the step needs the sums), and the product
	 * gathers one vector, where the textbook form needs a third barrier before q = Ap or, to
	 * avoid it, forms p = z + βp inside the product and gathers two. In exact arithmetic the
	 * iterates are the textbook's.
	 *
	 * The steps run in rounds of `chunk` iterations, each round its own parallel region, with
	 * the thread count sere_team gives at its start: a long solve on a machine that other
	 * processes start to load (or that was loaded when the solve began, before any measure)
	 * goes on with the cores left to it after a round, instead of stalling at every barrier
	 * for a thread that waits for its share of a busy core. A round is about 2²⁴ matrix
	 * entries of products (tens of ms): a small system (the maple's osmosis) runs its whole
	 * solve in one round, as before, and a 300 × 300 Poisson system in rounds of about 36 iterations,
	 * a fork and join per 10 ms or more. Blocks and their sums do not depend on the thread
	 * count, so neither do the iterates. */
	int done = 0;
	double b_norm = 0.0, rel = 0.0;
#pragma omp parallel num_threads( sere_team_default() )
	{
		/* Into positions; padding lanes get b = x = 0 and D⁻¹ = 0, so they stay 0 throughout
		 * and add nothing to any sum. s = p = 0, so that the first step's p = u + 0·p is u. */
#pragma omp for schedule( static ) reduction( | : bad_diagonal, nonfinite )
		for ( int32_t at = 0; at < np; ++at )
		{
			int32_t i = a->row[at];
			b[at] = i >= 0 ? b_in[i] : 0.0;
			x[at] = i >= 0 ? x_in[i] : 0.0;
			nonfinite |= !isfinite( b[at] ) || !isfinite( x[at] );
			double diagonal = a->diagonal[at] >= 0 ? a->val[a->diagonal[at]] : 0.0;
			bad_diagonal |= i >= 0 && !( diagonal > 0.0 );
			inv_diag[at] = diagonal > 0.0 ? 1.0 / diagonal : 0.0;
			p[at] = 0.0;
			s[at] = 0.0;
		}
		/* r = b − Ax, u = D⁻¹r */
#pragma omp for schedule( static )
		for ( int32_t blk = 0; blk < blocks; ++blk )
		{
			block_product( a, blk, x, w );
			double bb = 0.0, rr_block = 0.0;
			for ( int32_t i = blk * SERE_CG_BLOCK; i < block_end( blk, np ); ++i )
			{
				r[i] = b[i] - w[i];
				u[i] = inv_diag[i] * r[i];
				bb += b[i] * b[i];
				rr_block += r[i] * r[i];
			}
			partial[4 * blk] = rr_block;
			partial[4 * blk + 3] = bb;
		}
		double my_b_norm = sqrt( block_sum( partial, blocks, 3 ) );
		double my_rr = block_sum( partial, blocks, 0 );
		int my_done = bad_diagonal || nonfinite || !isfinite( my_rr );
		if ( !my_done && my_b_norm == 0.0 )
		{
#pragma omp for schedule( static )
			for ( int32_t i = 0; i < np; ++i )
			{
				x[i] = 0.0;
			}
			my_done = 1;
		}
		double my_rel = my_b_norm > 0.0 ? sqrt( my_rr ) / my_b_norm : 0.0;
		my_done = my_done || my_rel <= tolerance;
		if ( !my_done && max_iterations > 0 )
		{
#pragma omp for schedule( static )
			for ( int32_t blk = 0; blk < blocks; ++blk )
			{
				block_product_sums( a, blk, np, u, r, w, partial );
			}
		}
		/* every thread holds the same values; the region's end publishes the master's */
#pragma omp master
		{
			done = my_done;
			b_norm = my_b_norm;
			rel = my_rel;
		}
	}
	const int64_t chunk_entries = a->chunk_ptr[a->chunks] > 0 ? a->chunk_ptr[a->chunks] : 1;
	const int32_t chunk = (int32_t) ( ( 1 << 24 ) / chunk_entries > 16 ? ( 1 << 24 ) / chunk_entries : 16 );
	int32_t it = 0;
	double alpha_prev = 0.0, gamma_prev = 0.0;
	int local_status = SERE_OK;
	while ( !done && it < max_iterations )
	{
#pragma omp parallel num_threads( sere_team_default() )
		{
			int32_t my_it = it;
			double my_alpha_prev = alpha_prev, my_gamma_prev = gamma_prev, my_rel = rel;
			int my_status = SERE_OK, my_done = 0;
			const int32_t round_end = max_iterations - my_it > chunk ? my_it + chunk : max_iterations;
			while ( my_it < round_end )
			{
				double delta = block_sum( partial, blocks, 1 );
				double gamma = block_sum( partial, blocks, 2 );
				double beta = my_it == 0 ? 0.0 : gamma / my_gamma_prev;
				double pap = my_it == 0 ? delta : delta - beta * gamma / my_alpha_prev; /* pᵀAp */
				double alpha;
				my_status = cg_step_length( pap, gamma, &alpha );
				if ( my_status != SERE_OK )
				{
					my_done = 1;
					break;
				}
				/* p = u + βp, s = w + βs (= Ap), x += αp, r −= αs, u = D⁻¹r and rᵀr in one sweep */
#pragma omp for schedule( static )
				for ( int32_t blk = 0; blk < blocks; ++blk )
				{
					double rr_block = 0.0;
#pragma omp simd reduction( + : rr_block )
					for ( int32_t i = blk * SERE_CG_BLOCK; i < block_end( blk, np ); ++i )
					{
						p[i] = u[i] + beta * p[i];
						s[i] = w[i] + beta * s[i];
						x[i] += alpha * p[i];
						r[i] -= alpha * s[i];
						u[i] = inv_diag[i] * r[i];
						rr_block += r[i] * r[i];
					}
					partial[4 * blk] = rr_block;
				}
				/* rᵀr has a slot of its own: the product's sums never overwrite it, and the next
				 * step rewrites it only after every thread has passed the product's barrier, so
				 * after reading it here. */
				double my_rr = block_sum( partial, blocks, 0 );
				my_it += 1;
				my_rel = sqrt( my_rr ) / b_norm;
				if ( !isfinite( my_rel ) )
				{
					my_status = SERE_ERR_NONFINITE;
					my_done = 1;
					break;
				}
				if ( my_rel <= tolerance || my_it == max_iterations )
				{
					my_done = 1;
					break;
				}
#pragma omp for schedule( static )
				for ( int32_t blk = 0; blk < blocks; ++blk )
				{
					block_product_sums( a, blk, np, u, r, w, partial );
				}
				my_alpha_prev = alpha;
				my_gamma_prev = gamma;
			}
#pragma omp master
			{
				it = my_it;
				alpha_prev = my_alpha_prev;
				gamma_prev = my_gamma_prev;
				rel = my_rel;
				local_status = my_status;
				done = my_done;
			}
		}
	}
	/* Out of positions: the last iterate, whatever stopped the solve. */
#pragma omp parallel for num_threads( sere_team_default() ) schedule( static )
	for ( int32_t at = 0; at < np; ++at )
	{
		if ( a->row[at] >= 0 )
		{
			x_in[a->row[at]] = x[at];
		}
	}
	iterations = it;
	relative = rel;
	if ( bad_diagonal )
	{
		status = SERE_ERR_NOT_SPD;
	}
	else if ( nonfinite )
	{
		status = SERE_ERR_NONFINITE;
	}
	else if ( local_status != SERE_OK )
	{
		status = (sere_status) local_status;
	}
	else if ( rel > tolerance )
	{
		status = SERE_ERR_NO_CONVERGE;
	}
	result->iterations = iterations;
	result->residual = relative;
	return status;
}

void sere_sgs_destroy( sere_sgs* g )
{
	if ( g == NULL )
	{
		return;
	}
	sere_free( g->color_chunk );
	sere_free( g->color );
	sere_free( g->row );
	sere_free( g->lower_ptr );
	sere_free( g->upper_ptr );
	sere_free( g->col );
	sere_free( g->val );
	sere_free( g->slot );
	free( g );
}

static sere_status sgs_fail( sere_sgs* g, int32_t* scratch, sere_status status )
{
	free( scratch );
	sere_sgs_destroy( g );
	return status;
}

sere_status sere_sgs_create( const sere_csr* a, sere_sgs** out )
{
	if ( a == NULL || out == NULL || a->rows <= 0 || a->nnz < 0 || a->row_ptr == NULL || a->row_ptr[0] != 0 ||
		 a->row_ptr[a->rows] != a->nnz )
	{
		return SERE_ERR_ARGUMENT;
	}
	const int32_t n = a->rows;
	if ( !csr_indices_valid( a ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	sere_sgs* g = calloc( 1, sizeof( *g ) );
	/* scratch: per row its position, then per color its row count and next position */
	int32_t* scratch = malloc( sizeof( int32_t ) * ( (size_t) n + 2 * SERE_SGS_MAX_COLORS ) );
	if ( g == NULL || scratch == NULL )
	{
		return sgs_fail( g, scratch, SERE_ERR_MEMORY );
	}
	int32_t *position = scratch, *count = scratch + n, *next = count + SERE_SGS_MAX_COLORS;
	g->rows = n;
	g->nnz = a->nnz;
	g->color = sere_alloc( sizeof( int32_t ) * (size_t) n );
	g->color_chunk = sere_alloc( sizeof( int32_t ) * ( SERE_SGS_MAX_COLORS + 1 ) );
	if ( g->color == NULL || g->color_chunk == NULL )
	{
		return sgs_fail( g, scratch, SERE_ERR_MEMORY );
	}
	/* Greedy coloring in row order; a row must hold its diagonal exactly once. */
	memset( count, 0, sizeof( int32_t ) * SERE_SGS_MAX_COLORS );
	for ( int32_t i = 0; i < n; ++i )
	{
		uint32_t taken = 0;
		int32_t diagonals = 0;
		for ( int32_t k = a->row_ptr[i]; k < a->row_ptr[i + 1]; ++k )
		{
			int32_t j = a->col[k];
			diagonals += j == i;
			if ( j < i )
			{
				taken |= 1u << g->color[j];
			}
		}
		if ( diagonals != 1 || taken == UINT32_MAX )
		{
			return sgs_fail( g, scratch, SERE_ERR_ARGUMENT );
		}
		int32_t c = 0;
		while ( taken & ( 1u << c ) )
		{
			++c;
		}
		g->color[i] = c;
		count[c] += 1;
		g->colors = c + 1 > g->colors ? c + 1 : g->colors;
	}
	_Static_assert( SERE_SGS_MAX_COLORS == 32, "the taken colors are one 32-bit mask" );
	/* The pattern must be symmetric: a row's later neighbors chose their colors without it if
	 * they do not list it back, and M is SPD only for symmetric A. Rows are short (a scan each). */
	for ( int32_t i = 0; i < n; ++i )
	{
		for ( int32_t k = a->row_ptr[i]; k < a->row_ptr[i + 1]; ++k )
		{
			int32_t j = a->col[k], back = 0;
			for ( int32_t q = a->row_ptr[j]; q < a->row_ptr[j + 1] && !back; ++q )
			{
				back = a->col[q] == i;
			}
			if ( !back || ( j != i && g->color[j] == g->color[i] ) )
			{
				return sgs_fail( g, scratch, SERE_ERR_ARGUMENT );
			}
		}
	}
	g->color_chunk[0] = 0;
	for ( int32_t c = 0; c < g->colors; ++c )
	{
		g->color_chunk[c + 1] = g->color_chunk[c] + ( count[c] + LANES - 1 ) / LANES;
		next[c] = g->color_chunk[c] * LANES;
	}
	g->chunks = g->color_chunk[g->colors];
	const int32_t np = g->chunks * LANES;
	g->row = sere_alloc( sizeof( int32_t ) * (size_t) np );
	g->lower_ptr = sere_alloc( sizeof( int32_t ) * ( (size_t) g->chunks + 1 ) );
	g->upper_ptr = sere_alloc( sizeof( int32_t ) * ( (size_t) g->chunks + 1 ) );
	if ( g->row == NULL || g->lower_ptr == NULL || g->upper_ptr == NULL )
	{
		return sgs_fail( g, scratch, SERE_ERR_MEMORY );
	}
	for ( int32_t at = 0; at < np; ++at )
	{
		g->row[at] = -1;
	}
	/* Within a color, rows keep their order: neighbors in the numbering stay near in memory. */
	for ( int32_t i = 0; i < n; ++i )
	{
		position[i] = next[g->color[i]]++;
		g->row[position[i]] = i;
	}
	/* Slot counts: a chunk is as wide as its widest row's L (or U) part. */
	int64_t lower = 0, upper = 0;
	g->lower_ptr[0] = 0;
	for ( int32_t c = 0; c < g->colors; ++c )
	{
		for ( int32_t ch = g->color_chunk[c]; ch < g->color_chunk[c + 1]; ++ch )
		{
			int32_t lw = 0, uw = 0;
			for ( int32_t l = 0; l < LANES; ++l )
			{
				int32_t i = g->row[ch * LANES + l], nl = 0, nu = 0;
				for ( int32_t k = i >= 0 ? a->row_ptr[i] : 0; k < ( i >= 0 ? a->row_ptr[i + 1] : 0 ); ++k )
				{
					nl += g->color[a->col[k]] < c;
					nu += g->color[a->col[k]] > c;
				}
				lw = nl > lw ? nl : lw;
				uw = nu > uw ? nu : uw;
			}
			lower += (int64_t) lw * LANES;
			upper += (int64_t) uw * LANES;
			if ( lower + upper + np > INT32_MAX )
			{
				return sgs_fail( g, scratch, SERE_ERR_ARGUMENT );
			}
			g->lower_ptr[ch + 1] = (int32_t) lower;
			g->upper_ptr[ch + 1] = (int32_t) upper;
		}
	}
	g->upper_ptr[0] = 0;
	for ( int32_t ch = 0; ch <= g->chunks; ++ch )
	{
		g->upper_ptr[ch] += (int32_t) lower;
	}
	const size_t slots = (size_t) ( lower + upper );
	g->col = sere_alloc( sizeof( int32_t ) * ( slots > 0 ? slots : 1 ) );
	g->val = sere_alloc( sizeof( double ) * ( slots + (size_t) np ) );
	g->slot = sere_alloc( sizeof( int32_t ) * ( a->nnz > 0 ? (size_t) a->nnz : 1 ) );
	if ( g->col == NULL || g->val == NULL || g->slot == NULL )
	{
		return sgs_fail( g, scratch, SERE_ERR_MEMORY );
	}
	double* diagonal = g->val + slots;
	for ( int32_t ch = 0; ch < g->chunks; ++ch )
	{
		int32_t c = 0;
		while ( g->color_chunk[c + 1] <= ch )
		{
			++c;
		}
		for ( int32_t l = 0; l < LANES; ++l )
		{
			int32_t at = ch * LANES + l, i = g->row[at];
			/* Padding repeats the lane's own position with value 0: a read the lane makes anyway. */
			for ( int32_t s = g->lower_ptr[ch] + l; s < g->lower_ptr[ch + 1]; s += LANES )
			{
				g->col[s] = at;
				g->val[s] = 0.0;
			}
			for ( int32_t s = g->upper_ptr[ch] + l; s < g->upper_ptr[ch + 1]; s += LANES )
			{
				g->col[s] = at;
				g->val[s] = 0.0;
			}
			diagonal[at] = 1.0; /* padding: a lane of zeros stays zero through every sweep */
			if ( i < 0 )
			{
				continue;
			}
			int32_t sl = g->lower_ptr[ch] + l, su = g->upper_ptr[ch] + l;
			for ( int32_t k = a->row_ptr[i]; k < a->row_ptr[i + 1]; ++k )
			{
				int32_t j = a->col[k];
				int32_t s = g->color[j] < c ? sl : g->color[j] > c ? su : (int32_t) slots + at;
				sl += g->color[j] < c ? LANES : 0;
				su += g->color[j] > c ? LANES : 0;
				if ( j != i )
				{
					g->col[s] = position[j];
				}
				g->val[s] = a->val[k];
				g->slot[k] = s;
			}
		}
	}
	free( scratch );
	*out = g;
	return SERE_OK;
}

sere_status sere_sgs_update( sere_sgs* g, const sere_csr* a )
{
	if ( g == NULL || a == NULL || a->rows != g->rows || a->nnz != g->nnz )
	{
		return SERE_ERR_ARGUMENT;
	}
#pragma omp parallel for num_threads( sere_team_default() ) schedule( static )
	for ( int32_t k = 0; k < a->nnz; ++k )
	{
		g->val[g->slot[k]] = a->val[k];
	}
	return SERE_OK;
}

/* Sum over a chunk's slots [begin, end) of val · x[col], lane by lane in slot order. */
static inline void chunk_sum( const int32_t* col, const double* val, int32_t begin, int32_t end, const double* x,
							  lanes_t* out )
{
	half_t lo = { 0.0 }, hi = { 0.0 }, xlo, xhi;
	for ( int32_t s = begin; s < end; s += LANES )
	{
		gather( &xlo, x, col + s );
		gather( &xhi, x, col + s + 4 );
		lo += *(const half_t*) ( val + s ) * xlo;
		hi += *(const half_t*) ( val + s + 4 ) * xhi;
	}
	out->lo = lo;
	out->hi = hi;
}

/* Forward sweep z = L̃⁻¹ v in place (v in z on entry): color by color, each row
 * z_i = (v_i − Σ_L a_ij z_j) / d_i, the z_j of earlier colors already final. To be called by
 * every thread of a parallel region (the loop over a color's chunks is shared; its implicit
 * barrier orders the colors). */
static void sgs_forward( const sere_sgs* g, const double* inv_diag, double* z )
{
	for ( int32_t c = 0; c < g->colors; ++c )
	{
#pragma omp for schedule( static )
		for ( int32_t ch = g->color_chunk[c]; ch < g->color_chunk[c + 1]; ++ch )
		{
			lanes_t sum, v = load_lanes( z + ch * LANES ), inv = load_lanes( inv_diag + ch * LANES );
			chunk_sum( g->col, g->val, g->lower_ptr[ch], g->lower_ptr[ch + 1], z, &sum );
			v.lo = ( v.lo - sum.lo ) * inv.lo;
			v.hi = ( v.hi - sum.hi ) * inv.hi;
			store_lanes( z + ch * LANES, &v );
		}
	}
}

/* Backward sweep t = L̃⁻ᵀ u (t may be u): colors in reverse, t_i = (u_i − Σ_U a_ij t_j) / d_i;
 * the sums Σ_U a_ij t_j go to upper_sum (= u_i − d_i t_i in exact arithmetic), when not NULL. */
static void sgs_backward( const sere_sgs* g, const double* inv_diag, const double* u, double* t, double* upper_sum )
{
	for ( int32_t c = g->colors - 1; c >= 0; --c )
	{
#pragma omp for schedule( static )
		for ( int32_t ch = g->color_chunk[c]; ch < g->color_chunk[c + 1]; ++ch )
		{
			lanes_t sum, v = load_lanes( u + ch * LANES ), inv = load_lanes( inv_diag + ch * LANES );
			chunk_sum( g->col, g->val, g->upper_ptr[ch], g->upper_ptr[ch + 1], t, &sum );
			v.lo = ( v.lo - sum.lo ) * inv.lo;
			v.hi = ( v.hi - sum.hi ) * inv.hi;
			store_lanes( t + ch * LANES, &v );
			if ( upper_sum != NULL )
			{
				store_lanes( upper_sum + ch * LANES, &sum );
			}
		}
	}
}

/* y = A v for chunk ch: (L v + U v) + D v. */
static inline void sgs_chunk_product( const sere_sgs* g, int32_t ch, const double* v, double* y )
{
	const double* diagonal = g->val + g->upper_ptr[g->chunks];
	lanes_t lo, up, d = load_lanes( diagonal + ch * LANES ), x = load_lanes( v + ch * LANES );
	chunk_sum( g->col, g->val, g->lower_ptr[ch], g->lower_ptr[ch + 1], v, &lo );
	chunk_sum( g->col, g->val, g->upper_ptr[ch], g->upper_ptr[ch + 1], v, &up );
	lo.lo = ( lo.lo + up.lo ) + d.lo * x.lo;
	lo.hi = ( lo.hi + up.hi ) + d.hi * x.hi;
	store_lanes( y + ch * LANES, &lo );
}

sere_status sere_sgs_apply( const sere_sgs* g, const double* r, double* z )
{
	if ( g == NULL || r == NULL || z == NULL )
	{
		return SERE_ERR_ARGUMENT;
	}
	const int32_t np = g->chunks * LANES;
	const double* diagonal = g->val + g->upper_ptr[g->chunks];
	double *v = sere_alloc( sizeof( double ) * (size_t) np ), *inv = sere_alloc( sizeof( double ) * (size_t) np );
	if ( v == NULL || inv == NULL )
	{
		sere_free( v ), sere_free( inv );
		return SERE_ERR_MEMORY;
	}
	int bad = 0;
	for ( int32_t at = 0; at < np; ++at )
	{
		int32_t i = g->row[at];
		v[at] = i >= 0 ? r[i] : 0.0;
		bad |= i >= 0 && !( diagonal[at] > 0.0 );
		inv[at] = i >= 0 && diagonal[at] > 0.0 ? 1.0 / diagonal[at] : 0.0;
	}
	if ( !bad )
	{
		/* M⁻¹ r = L̃⁻ᵀ D L̃⁻¹ r */
#pragma omp parallel num_threads( sere_team_default() )
		{
			sgs_forward( g, inv, v );
#pragma omp for schedule( static )
			for ( int32_t at = 0; at < np; ++at )
			{
				v[at] = inv[at] > 0.0 ? diagonal[at] * v[at] : 0.0;
			}
			sgs_backward( g, inv, v, v, NULL );
		}
		for ( int32_t at = 0; at < np; ++at )
		{
			if ( g->row[at] >= 0 )
			{
				z[g->row[at]] = v[at];
			}
		}
	}
	sere_free( v ), sere_free( inv );
	return bad ? SERE_ERR_NOT_SPD : SERE_OK;
}

/* ŷ = L̃ᵀ x = D x + U x in place: colors in order, so a row's U columns (later colors) still
 * hold x when it reads them. Called by every thread of a region. */
static void sgs_upper_product( const sere_sgs* g, double* x )
{
	const double* diagonal = g->val + g->upper_ptr[g->chunks];
	for ( int32_t c = 0; c < g->colors; ++c )
	{
#pragma omp for schedule( static )
		for ( int32_t ch = g->color_chunk[c]; ch < g->color_chunk[c + 1]; ++ch )
		{
			lanes_t sum, d = load_lanes( diagonal + ch * LANES ), v = load_lanes( x + ch * LANES );
			chunk_sum( g->col, g->val, g->upper_ptr[ch], g->upper_ptr[ch + 1], x, &sum );
			v.lo = d.lo * v.lo + sum.lo;
			v.hi = d.hi * v.hi + sum.hi;
			store_lanes( x + ch * LANES, &v );
		}
	}
}

/* w = E u = t + L̃⁻¹ (u − D t), t = L̃⁻ᵀ u (Eisenstat), and the block sums of δ = uᵀw (slot 1):
 * the forward sweep forms each chunk's w and its lane-ordered share of δ, summed per block in
 * chunk order (the same bits for any thread count). Called by every thread of a region. */
static void sgs_product_sums( const sere_sgs* g, int32_t blocks, const double* inv_diag, const double* u, double* t,
							  double* z, double* w, double* chunk_delta, double* partial )
{
	sgs_backward( g, inv_diag, u, t, z );
	for ( int32_t c = 0; c < g->colors; ++c )
	{
#pragma omp for schedule( static )
		for ( int32_t ch = g->color_chunk[c]; ch < g->color_chunk[c + 1]; ++ch )
		{
			lanes_t sum, v = load_lanes( z + ch * LANES ), inv = load_lanes( inv_diag + ch * LANES );
			lanes_t tt = load_lanes( t + ch * LANES ), uu = load_lanes( u + ch * LANES );
			chunk_sum( g->col, g->val, g->lower_ptr[ch], g->lower_ptr[ch + 1], z, &sum );
			v.lo = ( v.lo - sum.lo ) * inv.lo;
			v.hi = ( v.hi - sum.hi ) * inv.hi;
			store_lanes( z + ch * LANES, &v );
			v.lo += tt.lo;
			v.hi += tt.hi;
			store_lanes( w + ch * LANES, &v );
			half_t d = uu.lo * v.lo + uu.hi * v.hi;
			chunk_delta[ch] = ( d[0] + d[1] ) + ( d[2] + d[3] );
		}
	}
#pragma omp for schedule( static )
	for ( int32_t blk = 0; blk < blocks; ++blk )
	{
		int32_t chunk_end = ( blk + 1 ) * CHUNKS_PER_BLOCK < g->chunks ? ( blk + 1 ) * CHUNKS_PER_BLOCK : g->chunks;
		double delta = 0.0;
		for ( int32_t ch = blk * CHUNKS_PER_BLOCK; ch < chunk_end; ++ch )
		{
			delta += chunk_delta[ch];
		}
		partial[4 * blk + 1] = delta;
	}
}

/* r = b − A x and its block sums of rᵀr (slot 0). Called by every thread of a region. */
static void sgs_residual( const sere_sgs* g, int32_t blocks, int32_t np, const double* b, const double* x, double* r,
						  double* partial )
{
#pragma omp for schedule( static )
	for ( int32_t blk = 0; blk < blocks; ++blk )
	{
		int32_t chunk_end = ( blk + 1 ) * CHUNKS_PER_BLOCK < g->chunks ? ( blk + 1 ) * CHUNKS_PER_BLOCK : g->chunks;
		for ( int32_t ch = blk * CHUNKS_PER_BLOCK; ch < chunk_end; ++ch )
		{
			sgs_chunk_product( g, ch, x, r );
		}
		double rr = 0.0;
#pragma omp simd reduction( + : rr )
		for ( int32_t i = blk * SERE_CG_BLOCK; i < block_end( blk, np ); ++i )
		{
			r[i] = b[i] - r[i];
			rr += r[i] * r[i];
		}
		partial[4 * blk] = rr;
	}
}

sere_status sere_cg_solve_sgs( sere_cg_workspace* ws, const sere_sgs* g, const double* b_in, double* x_in,
							   double tolerance, int32_t max_iterations, sere_cg_result* result )
{
	result->iterations = 0;
	result->residual = 0.0;
	if ( ws == NULL || g == NULL || b_in == NULL || x_in == NULL || g->rows <= 0 || g->rows > ws->capacity ||
		 g->chunks * LANES > ws->positions || !( tolerance >= 0.0 ) || max_iterations < 0 )
	{
		return SERE_ERR_ARGUMENT;
	}
	const int32_t np = g->chunks * LANES;
	const int32_t blocks = ( np + SERE_CG_BLOCK - 1 ) / SERE_CG_BLOCK;
	const double* diagonal = g->val + g->upper_ptr[g->chunks];
	double *x = ws->x, *b = ws->b, *r = ws->r, *u = ws->u, *w = ws->w, *p = ws->p, *s = ws->s;
	double *t = ws->t, *z = ws->z, *inv_diag = ws->inv_diag, *partial = ws->partial, *chunk_delta = ws->chunk_delta;
	int bad_diagonal = 0, nonfinite = 0;
#pragma omp parallel num_threads( sere_team_default() )
	{
#pragma omp for schedule( static ) reduction( | : bad_diagonal, nonfinite )
		for ( int32_t at = 0; at < np; ++at )
		{
			int32_t i = g->row[at];
			b[at] = i >= 0 ? b_in[i] : 0.0;
			x[at] = i >= 0 ? x_in[i] : 0.0;
			nonfinite |= !isfinite( b[at] ) || !isfinite( x[at] );
			bad_diagonal |= i >= 0 && !( diagonal[at] > 0.0 );
			inv_diag[at] = i >= 0 && diagonal[at] > 0.0 ? 1.0 / diagonal[at] : 0.0;
		}
#pragma omp for schedule( static )
		for ( int32_t blk = 0; blk < blocks; ++blk )
		{
			double bb = 0.0;
			for ( int32_t i = blk * SERE_CG_BLOCK; i < block_end( blk, np ); ++i )
			{
				bb += b[i] * b[i];
			}
			partial[4 * blk + 3] = bb;
		}
	}
	if ( bad_diagonal || nonfinite )
	{
		return bad_diagonal ? SERE_ERR_NOT_SPD : SERE_ERR_NONFINITE;
	}
	const double b_norm = sqrt( block_sum( partial, blocks, 3 ) );
	if ( b_norm == 0.0 )
	{
		for ( int32_t i = 0; i < g->rows; ++i )
		{
			x_in[i] = 0.0;
		}
		return SERE_OK;
	}
	const int64_t entries = g->upper_ptr[g->chunks] + np;
	const int32_t chunk = (int32_t) ( ( 1 << 24 ) / entries > 16 ? ( 1 << 24 ) / entries : 16 );
	int32_t it = 0;
	int local_status = SERE_OK;
	double rel = 0.0, safety = 1.0, previous = INFINITY;
	int met = 0; /* the last round's recursive residual reached its target */
	for ( ;; )
	{
		/* The true residual of x: the answer, or where (re)starting from x begins. */
		double rr_hat = 0.0;
#pragma omp parallel num_threads( sere_team_default() )
		{
			sgs_residual( g, blocks, np, b, x, r, partial );
		}
		rel = sqrt( block_sum( partial, blocks, 0 ) ) / b_norm;
		if ( !isfinite( rel ) )
		{
			local_status = SERE_ERR_NONFINITE;
			break;
		}
		/* Restart only while restarting still pays: below the rounding floor of b − A x
		 * itself (near 1e-14 relative on diffusion-dominated rows) the true residual stalls. */
		if ( rel <= tolerance || it >= max_iterations || local_status != SERE_OK || rel > 0.5 * previous )
		{
			break;
		}
		previous = rel;
		/* Into Eisenstat's variables: r̂ = L̃⁻¹ r, ŷ = L̃ᵀ x, u = D⁻¹ r̂, w = E u. s = p = 0 so that
		 * the first step's p = u + 0·p is u. */
#pragma omp parallel num_threads( sere_team_default() )
		{
			sgs_forward( g, inv_diag, r );
			sgs_upper_product( g, x );
#pragma omp for schedule( static )
			for ( int32_t blk = 0; blk < blocks; ++blk )
			{
				double rr = 0.0, gamma = 0.0;
				for ( int32_t i = blk * SERE_CG_BLOCK; i < block_end( blk, np ); ++i )
				{
					u[i] = diagonal[i] * r[i];
					p[i] = 0.0;
					s[i] = 0.0;
					rr += r[i] * r[i];
					gamma += r[i] * u[i];
				}
				partial[4 * blk] = rr;
				partial[4 * blk + 2 + ( it & 1 )] = gamma;
			}
			sgs_product_sums( g, blocks, inv_diag, u, t, z, w, chunk_delta, partial );
		}
		rr_hat = block_sum( partial, blocks, 0 );
		/* Reduce the transformed residual by the factor the true one still needs (and by half
		 * more at every restart, should the two norms have disagreed). */
		const double target = sqrt( rr_hat ) * ( tolerance / rel ) * safety;
		double alpha_prev = 0.0, gamma_prev = 0.0;
		int32_t first = it;
		int done = 0;
		while ( !done && it < max_iterations )
		{
#pragma omp parallel num_threads( sere_team_default() )
			{
				int32_t my_it = it;
				double my_alpha_prev = alpha_prev, my_gamma_prev = gamma_prev;
				int my_status = SERE_OK, my_done = 0, my_met = 0;
				const int32_t round_end = max_iterations - my_it > chunk ? my_it + chunk : max_iterations;
				while ( my_it < round_end )
				{
					double delta = block_sum( partial, blocks, 1 );
					/* γ = r̂ᵀu comes from the previous step's update sweep, into slot 2 or 3 by the
					 * parity of the step: a thread that runs ahead into this step's update writes
					 * the other slot while a slower one may still be reading this one. */
					double gamma = block_sum( partial, blocks, 2 + ( my_it & 1 ) );
					double beta = my_it == first ? 0.0 : gamma / my_gamma_prev;
					double pap = my_it == first ? delta : delta - beta * gamma / my_alpha_prev;
					double alpha;
					my_status = cg_step_length( pap, gamma, &alpha );
					if ( my_status != SERE_OK )
					{
						my_done = 1;
						break;
					}
#pragma omp for schedule( static )
					for ( int32_t blk = 0; blk < blocks; ++blk )
					{
						double rr_block = 0.0, gamma_block = 0.0;
#pragma omp simd reduction( + : rr_block, gamma_block )
						for ( int32_t i = blk * SERE_CG_BLOCK; i < block_end( blk, np ); ++i )
						{
							p[i] = u[i] + beta * p[i];
							s[i] = w[i] + beta * s[i];
							x[i] += alpha * p[i];
							r[i] -= alpha * s[i];
							u[i] = diagonal[i] * r[i];
							rr_block += r[i] * r[i];
							gamma_block += r[i] * u[i];
						}
						partial[4 * blk] = rr_block;
						partial[4 * blk + 2 + ( ( my_it + 1 ) & 1 )] = gamma_block;
					}
					double my_rr = block_sum( partial, blocks, 0 );
					my_it += 1;
					if ( !isfinite( my_rr ) )
					{
						my_status = SERE_ERR_NONFINITE;
						my_done = 1;
						break;
					}
					if ( sqrt( my_rr ) <= target || my_it == max_iterations )
					{
						my_met = sqrt( my_rr ) <= target;
						my_done = 1;
						break;
					}
					sgs_product_sums( g, blocks, inv_diag, u, t, z, w, chunk_delta, partial );
					my_alpha_prev = alpha;
					my_gamma_prev = gamma;
				}
#pragma omp master
				{
					it = my_it;
					alpha_prev = my_alpha_prev;
					gamma_prev = my_gamma_prev;
					local_status = my_status;
					done = my_done;
					met = my_met;
				}
			}
		}
		/* Back from ŷ: x = L̃⁻ᵀ ŷ. */
#pragma omp parallel num_threads( sere_team_default() )
		{
			sgs_backward( g, inv_diag, x, x, NULL );
		}
		safety *= 0.5;
	}
#pragma omp parallel for num_threads( sere_team_default() ) schedule( static )
	for ( int32_t at = 0; at < np; ++at )
	{
		if ( g->row[at] >= 0 )
		{
			x_in[g->row[at]] = x[at];
		}
	}
	result->iterations = it;
	result->residual = rel;
	if ( local_status != SERE_OK )
	{
		return (sere_status) local_status;
	}
	/* A true residual stalled above tolerance after the recursive one met it is rounding, not
	 * a lack of convergence: SERE_OK, as the Jacobi path (which checks only the recursive one)
	 * would return, with the true residual reported. */
	return rel <= tolerance || met ? SERE_OK : SERE_ERR_NO_CONVERGE;
}
