/* _GNU_SOURCE: sched_getaffinity for internal/team.h. */
#define _GNU_SOURCE

#include "solve/internal/cg_shared.h"

static inline double row_dot( const sere_csr* a, int32_t i, const double* x )
{
	double sum = 0.0;
	for ( int32_t k = a->row_ptr[i]; k < a->row_ptr[i + 1]; ++k )
	{
		sum += a->val[k] * x[a->col[k]];
	}
	return sum;
}

void sere_csr_spmv( const sere_csr* a, const double* x, double* y, int32_t threads )
{
#pragma omp parallel for num_threads( sere_team_for( threads ) ) schedule( static )
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

/* The chunks' columns, values and slots from the CSR rows (position: row → its lane), and
 * each lane's diagonal slot; false when a row holds its diagonal twice. */
static bool fill_chunks( sere_sell* s, const sere_csr* a, const int32_t* position )
{
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
					return false;
				}
				*diagonal = s->chunk_ptr[c] + k * LANES + l;
			}
		}
	}
	return true;
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
	bool filled = fill_chunks( s, a, position );
	free( position );
	if ( !filled )
	{
		sere_sell_destroy( s );
		return SERE_ERR_ARGUMENT;
	}
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
#pragma omp parallel for num_threads( sere_team_for( s->threads ) ) schedule( static ) reduction( | : mismatch )
	for ( int32_t k = 0; k < a->nnz; ++k )
	{
		s->val[s->slot[k]] = a->val[k];
		mismatch |= s->col[s->slot[k]] != a->col[k];
	}
	return mismatch ? SERE_ERR_ARGUMENT : SERE_OK;
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
#pragma omp parallel for num_threads( sere_team_for( a->threads ) ) schedule( static )
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

sere_status sere_sell_set_threads( sere_sell* sell, int32_t threads )
{
	return sell == NULL ? SERE_ERR_ARGUMENT : sere_threads_store( &sell->threads, threads );
}

sere_status sere_cg_set_threads( sere_cg_workspace* workspace, int32_t threads )
{
	return workspace == NULL ? SERE_ERR_ARGUMENT : sere_threads_store( &workspace->threads, threads );
}

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
	w->barrier = sere_alloc( sizeof( sere_spin_barrier ) );
	if ( failed || w->partial == NULL || w->chunk_delta == NULL || w->barrier == NULL )
	{
		sere_cg_destroy( w );
		return SERE_ERR_MEMORY;
	}
	memset( w->barrier, 0, sizeof( sere_spin_barrier ) );
	*out = w;
	return SERE_OK;
}

void sere_cg_destroy( sere_cg_workspace* w )
{
	if ( w == NULL )
	{
		return;
	}
	void* arrays[] = { w->x,		w->b, w->r, w->u,		w->w,			w->p,	   w->s,
					   w->inv_diag, w->t, w->z, w->partial, w->chunk_delta, w->barrier };
	sere_free_all( arrays, sizeof( arrays ) / sizeof( arrays[0] ) );
	free( w );
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

/* The solve's start: b and x into positions, D⁻¹, r = b − Ax, u = D⁻¹r, the first product's sums,
 * and whether the start already ends the solve. */
static void cg_start( cg_state* st, sere_cg_workspace* ws, const sere_sell* a, const double* b_in, const double* x_in,
					  double tolerance, int32_t max_iterations )
{
	const int32_t np = a->chunks * LANES; /* positions, the last chunk's padding lanes included */
	const int32_t blocks = ( np + SERE_CG_BLOCK - 1 ) / SERE_CG_BLOCK;
	double *x = ws->x, *b = ws->b, *r = ws->r, *u = ws->u, *w = ws->w, *p = ws->p, *s = ws->s;
	double *inv_diag = ws->inv_diag, *partial = ws->partial;
	int bad_diagonal = 0, nonfinite = 0;
#pragma omp parallel num_threads( sere_team_for( ws->threads ) )
	{
		/* Into positions; padding lanes get b = x = 0 and D⁻¹ = 0, so they stay 0 throughout
		 * and add nothing to any sum. s = p = 0, so that the first step's p = u + 0·p is u. */
#pragma omp for schedule( static ) reduction( | : bad_diagonal, nonfinite )
		for ( int32_t at = 0; at < np; ++at )
		{
			int32_t i = a->row[at];
			nonfinite |= load_position( i, b_in, x_in, b, x, at );
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
		double my_b_norm = sqrt( sere_block_sum( partial, blocks, 3 ) );
		double my_rr = sere_block_sum( partial, blocks, 0 );
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
			st->done = my_done;
			st->b_norm = my_b_norm;
			st->rel = my_rel;
		}
	}
	st->bad_diagonal = bad_diagonal;
	/* finite b and x with a NaN or infinite entry of A: the first residual shows it */
	st->nonfinite = nonfinite || !isfinite( st->rel );
}

/* One round of at most `chunk` steps of the recurrence, in one parallel region (see
 * sere_cg_solve). */
static void cg_round( cg_state* st, sere_cg_workspace* ws, const sere_sell* a, double tolerance, int32_t max_iterations,
					  int32_t chunk )
{
	const int32_t np = a->chunks * LANES; /* positions, the last chunk's padding lanes included */
	const int32_t blocks = ( np + SERE_CG_BLOCK - 1 ) / SERE_CG_BLOCK;
	double *x = ws->x, *r = ws->r, *u = ws->u, *w = ws->w, *p = ws->p, *s = ws->s;
	double *inv_diag = ws->inv_diag, *partial = ws->partial;
#pragma omp parallel num_threads( sere_team_for( ws->threads ) )
	{
		/* every thread steps its own copy; they stay equal */
		const int tid = omp_get_thread_num(), team = omp_get_num_threads();
		int32_t blk_first, blk_last;
		sere_team_share( 0, blocks, tid, team, &blk_first, &blk_last );
		cg_state my = *st;
		my.status = SERE_OK, my.done = 0, my.met = 0;
		const int32_t round_end = max_iterations - my.it > chunk ? my.it + chunk : max_iterations;
		while ( my.it < round_end )
		{
			double delta = sere_block_sum( partial, blocks, 1 );
			double gamma = sere_block_sum( partial, blocks, 2 );
			double beta = my.it == 0 ? 0.0 : gamma / my.gamma_prev;
			double pap = my.it == 0 ? delta : delta - beta * gamma / my.alpha_prev; /* pᵀAp */
			double alpha;
			my.status = cg_step_length( pap, gamma, &alpha );
			if ( my.status != SERE_OK )
			{
				my.done = 1;
				break;
			}
			/* p = u + βp, s = w + βs (= Ap), x += αp, r −= αs, u = D⁻¹r and rᵀr in one sweep */
			for ( int32_t blk = blk_first; blk < blk_last; ++blk )
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
			sere_spin_barrier_wait( ws->barrier, team );
			/* rᵀr has a slot of its own: the product's sums never overwrite it, and the next
			 * step rewrites it only after every thread has passed the product's barrier, so
			 * after reading it here. */
			double my_rr = sere_block_sum( partial, blocks, 0 );
			my.it += 1;
			my.rel = sqrt( my_rr ) / my.b_norm;
			if ( !isfinite( my.rel ) )
			{
				my.status = SERE_ERR_NONFINITE;
				my.done = 1;
				break;
			}
			if ( my.rel <= tolerance || my.it == max_iterations )
			{
				my.done = 1;
				break;
			}
			for ( int32_t blk = blk_first; blk < blk_last; ++blk )
			{
				block_product_sums( a, blk, np, u, r, w, partial );
			}
			sere_spin_barrier_wait( ws->barrier, team );
			my.alpha_prev = alpha;
			my.gamma_prev = gamma;
		}
#pragma omp master
		*st = my;
	}
}

sere_status sere_cg_solve( sere_cg_workspace* ws, const sere_sell* a, const double* b_in, double* x_in,
						   double tolerance, int32_t max_iterations, sere_cg_result* result )
{
	if ( result == NULL )
	{
		return SERE_ERR_ARGUMENT;
	}
	result->iterations = 0;
	result->residual = 0.0;
	if ( ws == NULL || a == NULL || b_in == NULL || x_in == NULL || a->rows <= 0 || a->rows > ws->capacity ||
		 a->sigma <= 0 || SERE_CG_BLOCK % a->sigma != 0 || !( tolerance >= 0.0 ) || max_iterations < 0 )
	{
		return SERE_ERR_ARGUMENT;
	}
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
	cg_state st = { 0 };
	cg_start( &st, ws, a, b_in, x_in, tolerance, max_iterations );
	const int64_t chunk_entries = a->chunk_ptr[a->chunks] > 0 ? a->chunk_ptr[a->chunks] : 1;
	const int32_t chunk = (int32_t) ( ( 1 << 24 ) / chunk_entries > 16 ? ( 1 << 24 ) / chunk_entries : 16 );
	while ( !st.done && st.it < max_iterations )
	{
		cg_round( &st, ws, a, tolerance, max_iterations, chunk );
	}
	/* Out of positions: the last iterate, whatever stopped the solve. */
	positions_to_rows( a->row, a->chunks * LANES, ws->x, x_in, ws->threads );
	sere_status status = SERE_OK;
	if ( st.bad_diagonal )
	{
		status = SERE_ERR_NOT_SPD;
	}
	else if ( st.nonfinite )
	{
		status = SERE_ERR_NONFINITE;
	}
	else if ( st.status != SERE_OK )
	{
		status = (sere_status) st.status;
	}
	else if ( st.rel > tolerance )
	{
		status = SERE_ERR_NO_CONVERGE;
	}
	result->iterations = st.it;
	result->residual = st.rel;
	return status;
}
