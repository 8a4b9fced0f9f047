/* sere — the symmetric Gauss–Seidel preconditioner of the conjugate gradient solver: its
 * chunked layout, the forward and backward sweeps, and sere_cg_solve_sgs.
 * _GNU_SOURCE: sched_getaffinity for internal/team.h. */
#define _GNU_SOURCE

#include "solve/internal/cg_shared.h"

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

/* Greedy coloring in row order (count: rows per color); false when a row does not hold its
 * diagonal exactly once, needs a 33rd color, or the pattern is not symmetric. */
static bool color_rows( sere_sgs* g, const sere_csr* a, int32_t* count )
{
	const int32_t n = a->rows;
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
			return false;
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
				return false;
			}
		}
	}
	return true;
}

/* Within windows of SERE_SGS_SIGMA positions of one color, rows sorted by their U then L length
 * (longest first), so that a chunk's eight rows are about as long on both sides and its slots
 * carry little padding (a chunk is as wide as its longest row). Rows of one color share no
 * entry, so their order within the color changes no row's sums; windows keep neighbours in the
 * numbering near in memory. */
static bool sort_windows( sere_sgs* g, const sere_csr* a, int32_t* position )
{
	row_length* keys = malloc( sizeof( row_length ) * SERE_SGS_SIGMA );
	if ( keys == NULL )
	{
		return false;
	}
	for ( int32_t c = 0; c < g->colors; ++c )
	{
		const int32_t begin = g->color_chunk[c] * LANES, end = g->color_chunk[c + 1] * LANES;
		for ( int32_t w = begin; w < end; w += SERE_SGS_SIGMA )
		{
			int32_t count = 0;
			for ( int32_t at = w; at < end && at < w + SERE_SGS_SIGMA && g->row[at] >= 0; ++at )
			{
				int32_t i = g->row[at], nl = 0, nu = 0;
				for ( int32_t k = a->row_ptr[i]; k < a->row_ptr[i + 1]; ++k )
				{
					nl += g->color[a->col[k]] < c;
					nu += g->color[a->col[k]] > c;
				}
				/* U length first, then L, as one key (exact for rows under 2048 entries; longer ones
				 * only sort less well) */
				keys[count++] = ( row_length ){ i, nu * ( SERE_SGS_MAX_COLORS * 64 ) + nl };
			}
			qsort( keys, (size_t) count, sizeof( row_length ), by_length );
			for ( int32_t k = 0; k < count; ++k )
			{
				g->row[w + k] = keys[k].row;
				position[keys[k].row] = w + k;
			}
		}
	}
	free( keys );
	return true;
}

/* The slots of every chunk from the CSR rows: the L part, the U part (columns as positions,
 * position: row → its position) and the diagonal after them; padding stays inert. */
static void fill_slots( sere_sgs* g, const sere_csr* a, const int32_t* position, size_t slots )
{
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
	if ( !color_rows( g, a, count ) )
	{
		return sgs_fail( g, scratch, SERE_ERR_ARGUMENT );
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
	if ( !sort_windows( g, a, position ) )
	{
		return sgs_fail( g, scratch, SERE_ERR_MEMORY );
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
	fill_slots( g, a, position, slots );
	free( scratch );
	*out = g;
	return SERE_OK;
}

sere_status sere_sgs_set_threads( sere_sgs* sgs, int32_t threads )
{
	return sgs == NULL ? SERE_ERR_ARGUMENT : sere_threads_store( &sgs->threads, threads );
}

sere_status sere_sgs_update( sere_sgs* g, const sere_csr* a )
{
	if ( g == NULL || a == NULL || a->rows != g->rows || a->nnz != g->nnz )
	{
		return SERE_ERR_ARGUMENT;
	}
#pragma omp parallel for num_threads( sere_team_for( g->threads ) ) schedule( static )
	for ( int32_t k = 0; k < a->nnz; ++k )
	{
		g->val[g->slot[k]] = a->val[k];
	}
	return SERE_OK;
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
			sweep_chunk( g, g->lower_ptr, ch, inv_diag, z, z, NULL );
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
			sweep_chunk( g, g->upper_ptr, ch, inv_diag, u, t, upper_sum );
		}
	}
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
#pragma omp parallel num_threads( sere_team_for( g->threads ) )
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

/* Forward chunk ch of E u: z = (z − Σ_L a_ij z_j) / d, z holding the backward sweep's upper
 * sums on entry, then w = z + t and the chunk's lane-ordered share of δ = uᵀw. */
static inline void forward_product_chunk( const sere_sgs* g, int32_t ch, const double* inv_diag, const double* u,
										  const double* t, double* z, double* w, double* chunk_delta )
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

/* w = E u = t + L̃⁻¹ (u − D t), t = L̃⁻ᵀ u (Eisenstat); returns δ = uᵀw. The backward sweep runs
 * colors from_color down to 1 (the update loop of sgs_round has done the last color, which has
 * no U entries, when from_color is colors − 2). Color 0 has no L entries, so its forward rows
 * need only their own chunk's backward result: both run chunk by chunk in one loop. Then the
 * forward sweep's other colors form each chunk's w and share of δ. Every thread sums the shares
 * itself, per block in chunk order and then block by block (sere_block_sum's order, the same bits for
 * any thread count), after the last color's barrier: per iteration, two colors' barriers and a
 * summing pass fewer than sweeping each color of both sweeps on its own. The colors meet at the
 * workspace's spin barrier, not at an `omp for`'s: libgomp's makes a system call at each of the
 * 2·colors − 1 barriers of an iteration, one thread or two (team.h). Called by every thread of a
 * region. */
static double sgs_product_sums( const sere_sgs* g, int32_t from_color, const double* inv_diag, const double* u,
								double* t, double* z, double* w, double* chunk_delta, sere_spin_barrier* barrier )
{
	const int tid = omp_get_thread_num(), team = omp_get_num_threads();
	int32_t first, last;
	for ( int32_t c = from_color; c >= 1; --c )
	{
		sere_team_share( g->color_chunk[c], g->color_chunk[c + 1], tid, team, &first, &last );
		for ( int32_t ch = first; ch < last; ++ch )
		{
			sweep_chunk( g, g->upper_ptr, ch, inv_diag, u, t, z );
		}
		sere_spin_barrier_wait( barrier, team );
	}
	sere_team_share( g->color_chunk[0], g->color_chunk[1], tid, team, &first, &last );
	for ( int32_t ch = first; ch < last; ++ch )
	{
		sweep_chunk( g, g->upper_ptr, ch, inv_diag, u, t, z );
		forward_product_chunk( g, ch, inv_diag, u, t, z, w, chunk_delta );
	}
	sere_spin_barrier_wait( barrier, team );
	for ( int32_t c = 1; c < g->colors; ++c )
	{
		sere_team_share( g->color_chunk[c], g->color_chunk[c + 1], tid, team, &first, &last );
		for ( int32_t ch = first; ch < last; ++ch )
		{
			forward_product_chunk( g, ch, inv_diag, u, t, z, w, chunk_delta );
		}
		sere_spin_barrier_wait( barrier, team );
	}
	double delta = 0.0;
	for ( int32_t begin = 0; begin < g->chunks; begin += CHUNKS_PER_BLOCK )
	{
		const int32_t end = begin + CHUNKS_PER_BLOCK < g->chunks ? begin + CHUNKS_PER_BLOCK : g->chunks;
		double block = 0.0;
		for ( int32_t ch = begin; ch < end; ++ch )
		{
			block += chunk_delta[ch];
		}
		delta += block;
	}
	return delta;
}

/* The solve's start: b and x into positions, D⁻¹ and the blocks' sums of b²; flags a diagonal
 * that is not positive and a non-finite input, and tells whether x is +0 in every position (a
 * cold start, whose A x and L̃ᵀ x are +0 without a product). */
static void sgs_start( cg_state* st, sere_cg_workspace* ws, const sere_sgs* g, const double* b_in, const double* x_in,
					   bool* x_zero )
{
	const int32_t np = g->chunks * LANES;
	const int32_t blocks = ( np + SERE_CG_BLOCK - 1 ) / SERE_CG_BLOCK;
	const double* diagonal = g->val + g->upper_ptr[g->chunks];
	double *x = ws->x, *b = ws->b, *inv_diag = ws->inv_diag, *partial = ws->partial;
	int bad_diagonal = 0, nonfinite = 0, nonzero = 0;
#pragma omp parallel num_threads( sere_team_for( ws->threads ) )
	{
#pragma omp for schedule( static ) reduction( | : bad_diagonal, nonfinite, nonzero )
		for ( int32_t at = 0; at < np; ++at )
		{
			int32_t i = g->row[at];
			nonfinite |= load_position( i, b_in, x_in, b, x, at );
			nonzero |= x[at] != 0.0 || signbit( x[at] );
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
	st->bad_diagonal = bad_diagonal;
	st->nonfinite = nonfinite;
	*x_zero = !nonzero;
}

/* Into Eisenstat's variables: r̂ = L̃⁻¹ r, ŷ = L̃ᵀ x (x itself when x_zero: +0 stays +0), u = D⁻¹ r̂,
 * w = E u. s = p = 0 so that the first step's p = u + 0·p is u. Returns r̂ᵀr̂; δ = uᵀw goes to
 * *delta. */
static double sgs_restart( sere_cg_workspace* ws, const sere_sgs* g, int32_t it, bool x_zero, double* delta )
{
	const int32_t np = g->chunks * LANES;
	const int32_t blocks = ( np + SERE_CG_BLOCK - 1 ) / SERE_CG_BLOCK;
	const double* diagonal = g->val + g->upper_ptr[g->chunks];
	double *x = ws->x, *r = ws->r, *u = ws->u, *w = ws->w, *p = ws->p, *s = ws->s;
	double *t = ws->t, *z = ws->z, *inv_diag = ws->inv_diag, *partial = ws->partial, *chunk_delta = ws->chunk_delta;
#pragma omp parallel num_threads( sere_team_for( ws->threads ) )
	{
		sgs_forward( g, inv_diag, r );
		if ( !x_zero )
		{
			sgs_upper_product( g, x );
		}
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
		double d = sgs_product_sums( g, g->colors - 1, inv_diag, u, t, z, w, chunk_delta, ws->barrier );
#pragma omp master
		*delta = d;
	}
	return sere_block_sum( partial, blocks, 0 );
}

/* One round of at most `chunk` steps of the recurrence from step `first`, in one parallel region
 * (as sere_cg_solve's rounds), until the recursive residual reaches target. */
static void sgs_round( cg_state* st, sere_cg_workspace* ws, const sere_sgs* g, int32_t first, double target,
					   int32_t max_iterations, int32_t chunk )
{
	const int32_t np = g->chunks * LANES;
	const int32_t blocks = ( np + SERE_CG_BLOCK - 1 ) / SERE_CG_BLOCK;
	const double* diagonal = g->val + g->upper_ptr[g->chunks];
	double *x = ws->x, *r = ws->r, *u = ws->u, *w = ws->w, *p = ws->p, *s = ws->s;
	double *t = ws->t, *z = ws->z, *inv_diag = ws->inv_diag, *partial = ws->partial, *chunk_delta = ws->chunk_delta;
	/* The last color's rows have no U entries: their backward rows t = u / d (upper sums 0) are
	 * done in the update loop, beside the u they read, when there is more than one color. */
	const int32_t last_first = g->colors > 1 ? g->color_chunk[g->colors - 1] * LANES : np;
	const int32_t from_color = g->colors > 1 ? g->colors - 2 : 0;
#pragma omp parallel num_threads( sere_team_for( ws->threads ) )
	{
		/* every thread steps its own copy; they stay equal */
		const int tid = omp_get_thread_num(), team = omp_get_num_threads();
		const owned_blocks own = blocks_of_thread( g, tid, team );
		cg_state my = *st;
		my.status = SERE_OK, my.done = 0, my.met = 0;
		const int32_t round_end = max_iterations - my.it > chunk ? my.it + chunk : max_iterations;
		while ( my.it < round_end )
		{
			double delta = my.delta;
			/* γ = r̂ᵀu comes from the previous step's update sweep, into slot 2 or 3 by the
			 * parity of the step: a thread that runs ahead into this step's update writes
			 * the other slot while a slower one may still be reading this one. */
			double gamma = sere_block_sum( partial, blocks, 2 + ( my.it & 1 ) );
			double beta = my.it == first ? 0.0 : gamma / my.gamma_prev;
			double pap = my.it == first ? delta : delta - beta * gamma / my.alpha_prev;
			double alpha;
			my.status = cg_step_length( pap, gamma, &alpha );
			if ( my.status != SERE_OK )
			{
				my.done = 1;
				break;
			}
			for ( int32_t blk = owned_block_next( &own, -1 ); blk >= 0; blk = owned_block_next( &own, blk ) )
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
				partial[4 * blk + 2 + ( ( my.it + 1 ) & 1 )] = gamma_block;
				for ( int32_t i = last_first > blk * SERE_CG_BLOCK ? last_first : blk * SERE_CG_BLOCK;
					  i < block_end( blk, np ); ++i )
				{
					t[i] = u[i] * inv_diag[i];
					z[i] = 0.0;
				}
			}
			sere_spin_barrier_wait( ws->barrier, team );
			if ( cg_step_done( &my, sere_block_sum( partial, blocks, 0 ), target, max_iterations ) )
			{
				break;
			}
			my.delta = sgs_product_sums( g, from_color, inv_diag, u, t, z, w, chunk_delta, ws->barrier );
			my.alpha_prev = alpha;
			my.gamma_prev = gamma;
		}
#pragma omp master
		*st = my;
	}
}

sere_status sere_cg_solve_sgs( sere_cg_workspace* ws, const sere_sgs* g, const double* b_in, double* x_in,
							   double tolerance, int32_t max_iterations, sere_cg_result* result )
{
	if ( result == NULL )
	{
		return SERE_ERR_ARGUMENT;
	}
	result->iterations = 0;
	result->residual = 0.0;
	if ( ws == NULL || g == NULL || b_in == NULL || x_in == NULL || g->rows <= 0 || g->rows > ws->capacity ||
		 g->chunks * LANES > ws->positions || !( tolerance >= 0.0 ) || max_iterations < 0 )
	{
		return SERE_ERR_ARGUMENT;
	}
	const int32_t np = g->chunks * LANES;
	const int32_t blocks = ( np + SERE_CG_BLOCK - 1 ) / SERE_CG_BLOCK;
	double *x = ws->x, *b = ws->b, *r = ws->r, *inv_diag = ws->inv_diag, *partial = ws->partial;
	cg_state st = { 0 };
	bool x_zero;
	sgs_start( &st, ws, g, b_in, x_in, &x_zero );
	if ( st.bad_diagonal || st.nonfinite )
	{
		return st.bad_diagonal ? SERE_ERR_NOT_SPD : SERE_ERR_NONFINITE;
	}
	const double b_norm = sqrt( sere_block_sum( partial, blocks, 3 ) );
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
	double rel = 0.0, safety = 1.0, previous = INFINITY;
	/* U x of the x the residual measures, once a backward sweep has left it in z (NULL before) */
	const double* upper = NULL;
	for ( ;; )
	{
		/* The true residual of x: the answer, or where (re)starting from x begins. */
#pragma omp parallel num_threads( sere_team_for( ws->threads ) )
		{
			int32_t first, last;
			sere_team_share( 0, blocks, omp_get_thread_num(), omp_get_num_threads(), &first, &last );
			sgs_residual_blocks( g, first, last, np, b, x_zero ? NULL : x, upper, r, partial );
		}
		rel = sqrt( sere_block_sum( partial, blocks, 0 ) ) / b_norm;
		if ( !isfinite( rel ) )
		{
			st.status = SERE_ERR_NONFINITE;
			break;
		}
		/* Restart only while restarting still pays: below the rounding floor of b − A x
		 * itself (near 1e-14 relative on diffusion-dominated rows) the true residual stalls. */
		if ( rel <= tolerance || st.it >= max_iterations || st.status != SERE_OK || rel > 0.5 * previous )
		{
			break;
		}
		previous = rel;
		double rr_hat = sgs_restart( ws, g, st.it, x_zero, &st.delta );
		/* Reduce the transformed residual by the factor the true one still needs (and by half
		 * more at every restart, should the two norms have disagreed). */
		const double target = sqrt( rr_hat ) * ( tolerance / rel ) * safety;
		st.alpha_prev = 0.0, st.gamma_prev = 0.0;
		int32_t first = st.it;
		st.done = 0;
		while ( !st.done && st.it < max_iterations )
		{
			sgs_round( &st, ws, g, first, target, max_iterations, chunk );
		}
		/* Back from ŷ: x = L̃⁻ᵀ ŷ, its rows' U sums kept in z for the next residual (z is the
		 * rounds' scratch, free until the next restart). */
#pragma omp parallel num_threads( sere_team_for( ws->threads ) )
		{
			sgs_backward( g, inv_diag, x, x, ws->z );
		}
		upper = ws->z;
		x_zero = false;
		safety *= 0.5;
	}
	positions_to_rows( g->row, np, x, x_in, ws->threads );
	result->iterations = st.it;
	result->residual = rel;
	if ( st.status != SERE_OK )
	{
		return (sere_status) st.status;
	}
	/* A true residual stalled above tolerance after the recursive one met it is rounding, not
	 * a lack of convergence: SERE_OK, as the Jacobi path (which checks only the recursive one)
	 * would return, with the true residual reported. */
	return rel <= tolerance || st.met ? SERE_OK : SERE_ERR_NO_CONVERGE;
}

sere_status sere_cg_residual_sgs( sere_cg_workspace* ws, const sere_sgs* g, const double* b_in, const double* x_in,
								  double* relative )
{
	if ( ws == NULL || g == NULL || b_in == NULL || x_in == NULL || relative == NULL || g->rows <= 0 ||
		 g->rows > ws->capacity || g->chunks * LANES > ws->positions )
	{
		return SERE_ERR_ARGUMENT;
	}
	const int32_t np = g->chunks * LANES;
	const int32_t blocks = ( np + SERE_CG_BLOCK - 1 ) / SERE_CG_BLOCK;
	double *x = ws->x, *b = ws->b, *r = ws->r, *partial = ws->partial;
	int nonfinite = 0;
#pragma omp parallel num_threads( sere_team_for( ws->threads ) )
	{
#pragma omp for schedule( static ) reduction( | : nonfinite )
		for ( int32_t at = 0; at < np; ++at )
		{
			nonfinite |= load_position( g->row[at], b_in, x_in, b, x, at );
		}
		int32_t first, last;
		sere_team_share( 0, blocks, omp_get_thread_num(), omp_get_num_threads(), &first, &last );
		sgs_residual_blocks( g, first, last, np, b, x, NULL, r, partial );
		for ( int32_t blk = first; blk < last; ++blk )
		{
			partial[4 * blk + 3] = dot_lanes( b, b, blk * SERE_CG_BLOCK, block_end( blk, np ) );
		}
	}
	if ( nonfinite )
	{
		return SERE_ERR_NONFINITE;
	}
	const double rr = sere_block_sum( partial, blocks, 0 ), bb = sere_block_sum( partial, blocks, 3 );
	*relative = bb > 0.0 ? sqrt( rr / bb ) : rr > 0.0 ? INFINITY : 0.0;
	return SERE_OK;
}

/* The floor's chunk of the backward sweep: u and D⁻¹ read, the chunk's U entries read and t
 * gathered at their columns, t and the upper sums (z) stored. */
static inline void backward_touch_chunk( const sere_sgs* g, int32_t ch, const double* inv_diag, const double* u,
										 double* t, double* z )
{
	lanes_t up, v = load_lanes( u + ch * LANES ), inv = load_lanes( inv_diag + ch * LANES );
	chunk_pass( g->col, g->val, g->upper_ptr[ch], g->upper_ptr[ch + 1], t, true, &up );
	v.lo = v.lo + up.lo + inv.lo;
	v.hi = v.hi + up.hi + inv.hi;
	store_lanes( t + ch * LANES, &v );
	store_lanes( z + ch * LANES, &up );
}

/* The floor's forward_product_chunk: z, D⁻¹, t and u read, the L entries read and z gathered, z
 * and w stored, the chunk's share of δ. */
static inline void forward_touch_chunk( const sere_sgs* g, int32_t ch, const double* inv_diag, const double* u,
										const double* t, double* z, double* w, double* chunk_delta )
{
	lanes_t lo, v = load_lanes( z + ch * LANES ), inv = load_lanes( inv_diag + ch * LANES );
	lanes_t tt = load_lanes( t + ch * LANES ), uu = load_lanes( u + ch * LANES );
	chunk_pass( g->col, g->val, g->lower_ptr[ch], g->lower_ptr[ch + 1], z, true, &lo );
	v.lo = v.lo + lo.lo + inv.lo;
	v.hi = v.hi + lo.hi + inv.hi;
	store_lanes( z + ch * LANES, &v );
	v.lo += tt.lo;
	v.hi += tt.hi;
	store_lanes( w + ch * LANES, &v );
	half_t d = uu.lo + v.lo + uu.hi + v.hi;
	chunk_delta[ch] = ( d[0] + d[1] ) + ( d[2] + d[3] );
}

sere_status sere_cg_touch_sgs( sere_cg_workspace* ws, const sere_sgs* g, int32_t iterations )
{
	if ( ws == NULL || g == NULL || iterations < 0 || g->rows <= 0 || g->rows > ws->capacity ||
		 g->chunks * LANES > ws->positions )
	{
		return SERE_ERR_ARGUMENT;
	}
	const int32_t np = g->chunks * LANES;
	const double* diagonal = g->val + g->upper_ptr[g->chunks];
	double *x = ws->x, *r = ws->r, *u = ws->u, *w = ws->w, *p = ws->p, *s = ws->s;
	double *t = ws->t, *z = ws->z, *inv_diag = ws->inv_diag, *partial = ws->partial, *chunk_delta = ws->chunk_delta;
	/* from zero every call: the adds then stay far from overflow over a solve's iterations */
	double* vectors[9] = { x, r, u, w, p, s, t, z, inv_diag };
	for ( int v = 0; v < 9; ++v )
	{
		memset( vectors[v], 0, sizeof( double ) * (size_t) np );
	}
	/* as sgs_round: the last color's backward rows in the update pass */
	const int32_t last_first = g->colors > 1 ? g->color_chunk[g->colors - 1] * LANES : np;
	const int32_t from_color = g->colors > 1 ? g->colors - 2 : 0;
	double delta_sink = 0.0;
#pragma omp parallel num_threads( sere_team_for( ws->threads ) )
	{
		const int tid = omp_get_thread_num(), team = omp_get_num_threads();
		const owned_blocks own = blocks_of_thread( g, tid, team );
		int32_t first, last;
		double delta = 0.0;
		for ( int32_t it = 0; it < iterations; ++it )
		{
			for ( int32_t blk = owned_block_next( &own, -1 ); blk >= 0; blk = owned_block_next( &own, blk ) )
			{
				double rr_block = 0.0, gamma_block = 0.0;
#pragma omp simd reduction( + : rr_block, gamma_block )
				for ( int32_t i = blk * SERE_CG_BLOCK; i < block_end( blk, np ); ++i )
				{
					p[i] = u[i] + p[i];
					s[i] = w[i] + s[i];
					x[i] += p[i];
					r[i] += s[i];
					u[i] = diagonal[i] + r[i];
					rr_block += r[i];
					gamma_block += u[i];
				}
				partial[4 * blk] = rr_block;
				partial[4 * blk + 2 + ( ( it + 1 ) & 1 )] = gamma_block;
				for ( int32_t i = last_first > blk * SERE_CG_BLOCK ? last_first : blk * SERE_CG_BLOCK;
					  i < block_end( blk, np ); ++i )
				{
					t[i] = u[i] + inv_diag[i];
					z[i] = 0.0;
				}
			}
			sere_spin_barrier_wait( ws->barrier, team );
			for ( int32_t c = from_color; c >= 1; --c )
			{
				sere_team_share( g->color_chunk[c], g->color_chunk[c + 1], tid, team, &first, &last );
				for ( int32_t ch = first; ch < last; ++ch )
				{
					backward_touch_chunk( g, ch, inv_diag, u, t, z );
				}
				sere_spin_barrier_wait( ws->barrier, team );
			}
			sere_team_share( g->color_chunk[0], g->color_chunk[1], tid, team, &first, &last );
			for ( int32_t ch = first; ch < last; ++ch )
			{
				backward_touch_chunk( g, ch, inv_diag, u, t, z );
				forward_touch_chunk( g, ch, inv_diag, u, t, z, w, chunk_delta );
			}
			sere_spin_barrier_wait( ws->barrier, team );
			for ( int32_t c = 1; c < g->colors; ++c )
			{
				sere_team_share( g->color_chunk[c], g->color_chunk[c + 1], tid, team, &first, &last );
				for ( int32_t ch = first; ch < last; ++ch )
				{
					forward_touch_chunk( g, ch, inv_diag, u, t, z, w, chunk_delta );
				}
				sere_spin_barrier_wait( ws->barrier, team );
			}
			/* every thread reads every chunk's share, as sgs_product_sums does */
			for ( int32_t ch = 0; ch < g->chunks; ++ch )
			{
				delta += chunk_delta[ch];
			}
		}
#pragma omp master
		delta_sink = delta;
	}
	/* the shares' sum stored, so that the loop reading them stays */
	partial[0] = delta_sink;
	return SERE_OK;
}
