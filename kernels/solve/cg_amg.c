/* sere — the aggregation multigrid preconditioner of the conjugate gradient solver (cg.h):
 * building the levels, refreshing their values, the V-cycle, and sere_cg_solve_amg.
 * _GNU_SOURCE: sched_getaffinity for internal/team.h. */
#define _GNU_SOURCE

#include "solve/internal/amg_shared.h"

void sere_amg_destroy( sere_amg* m )
{
	if ( m == NULL )
	{
		return;
	}
	for ( int32_t l = 0; l < SERE_AMG_MAX_LEVELS; ++l )
	{
		amg_level* L = &m->level[l];
		void* arrays[] = { L->coarse_at, L->member_ptr, L->member, L->sum_to, L->sum_ptr,
						   L->sum_from,	 L->x,			L->b,	   L->r,	  L->inv_diag };
		sere_free_all( arrays, sizeof( arrays ) / sizeof( arrays[0] ) );
		sere_sgs_destroy( L->own );
	}
	void* arrays[] = { m->dense, m->factor, m->dense_b, m->dense_x, m->barrier };
	sere_free_all( arrays, sizeof( arrays ) / sizeof( arrays[0] ) );
	free( m );
}

/* Aggregates of a's rows from its pattern: each row whose neighbors are all still free starts
 * one with them (rows in order), then every row left joins the aggregate its first grouped
 * neighbor had after that pass (every row left has one: a neighbor was grouped when it was
 * passed). agg[i] per row; returns the count. */
static int32_t aggregate( const sere_csr* a, int32_t* agg, int32_t* pick )
{
	int32_t count = 0;
	for ( int32_t i = 0; i < a->rows; ++i )
	{
		agg[i] = -1;
	}
	for ( int32_t i = 0; i < a->rows; ++i )
	{
		bool fresh = agg[i] < 0;
		for ( int32_t k = a->row_ptr[i]; k < a->row_ptr[i + 1] && fresh; ++k )
		{
			fresh = agg[a->col[k]] < 0;
		}
		if ( fresh )
		{
			agg[i] = count;
			for ( int32_t k = a->row_ptr[i]; k < a->row_ptr[i + 1]; ++k )
			{
				agg[a->col[k]] = count;
			}
			count += 1;
		}
	}
	for ( int32_t i = 0; i < a->rows; ++i )
	{
		pick[i] = agg[i];
		for ( int32_t k = a->row_ptr[i]; k < a->row_ptr[i + 1] && pick[i] < 0; ++k )
		{
			pick[i] = agg[a->col[k]];
		}
	}
	memcpy( agg, pick, sizeof( int32_t ) * (size_t) a->rows );
	return count;
}

/* The pattern of Pᵀ A P: c gets one row per aggregate, its columns ascending, and target[k] the
 * entry of c that a's entry k adds to. mark and list are scratch of count entries. */
static sere_status coarse_pattern( const sere_csr* a, const int32_t* agg, int32_t count, sere_csr* c, int32_t* target,
								   int32_t* mark, int32_t* list )
{
	int32_t* first = malloc( sizeof( int32_t ) * ( (size_t) count + 1 ) );
	int32_t* rows = malloc( sizeof( int32_t ) * (size_t) a->rows );
	c->rows = count;
	c->row_ptr = sere_alloc( sizeof( int32_t ) * ( (size_t) count + 1 ) );
	c->col = sere_alloc( sizeof( int32_t ) * (size_t) a->nnz );
	c->val = sere_alloc( sizeof( double ) * (size_t) a->nnz );
	if ( first == NULL || rows == NULL || c->row_ptr == NULL || c->col == NULL || c->val == NULL )
	{
		free( first ), free( rows );
		return SERE_ERR_MEMORY;
	}
	/* the rows of each aggregate, ascending */
	memset( first, 0, sizeof( int32_t ) * ( (size_t) count + 1 ) );
	for ( int32_t i = 0; i < a->rows; ++i )
	{
		first[agg[i] + 1] += 1;
	}
	for ( int32_t g = 0; g < count; ++g )
	{
		first[g + 1] += first[g];
		mark[g] = -1;
	}
	for ( int32_t i = 0; i < a->rows; ++i )
	{
		rows[first[agg[i]]++] = i;
	}
	int32_t nnz = 0, at = 0;
	c->row_ptr[0] = 0;
	for ( int32_t g = 0; g < count; ++g )
	{
		int32_t begin = at, length = 0;
		for ( ; at < a->rows && agg[rows[at]] == g; ++at )
		{
			for ( int32_t k = a->row_ptr[rows[at]]; k < a->row_ptr[rows[at] + 1]; ++k )
			{
				int32_t h = agg[a->col[k]];
				if ( mark[h] != g )
				{
					mark[h] = g;
					list[length++] = h;
				}
			}
		}
		for ( int32_t s = 1; s < length; ++s ) /* a row is short: insertion sort */
		{
			int32_t v = list[s], t = s;
			for ( ; t > 0 && list[t - 1] > v; --t )
			{
				list[t] = list[t - 1];
			}
			list[t] = v;
		}
		for ( int32_t s = 0; s < length; ++s )
		{
			c->col[nnz + s] = list[s];
			first[list[s]] = nnz + s; /* first is free now: per column, its entry in this row */
		}
		for ( int32_t q = begin; q < at; ++q )
		{
			for ( int32_t k = a->row_ptr[rows[q]]; k < a->row_ptr[rows[q] + 1]; ++k )
			{
				target[k] = first[agg[a->col[k]]];
			}
		}
		nnz += length;
		c->row_ptr[g + 1] = nnz;
	}
	c->nnz = nnz;
	memset( c->val, 0, sizeof( double ) * (size_t) a->nnz );
	free( first ), free( rows );
	return SERE_OK;
}

/* One contribution to a Galerkin sum. Within a target the sources are taken in the order of
 * (min(i, j), max(i, j), i) of their entries a_ij, the same order for the mirrored target, so a
 * symmetric A gives bitwise symmetric coarse matrices. */
typedef struct amg_term
{
	int32_t target, low, high, row, source;
} amg_term;

typedef enum term_key
{
	KEY_HIGH,
	KEY_LOW,
	KEY_TARGET
} term_key;

static inline int32_t key_of( const amg_term* t, term_key key )
{
	return key == KEY_HIGH ? t->high : key == KEY_LOW ? t->low : t->target;
}

/* A stable counting sort of n terms from in to out by their key, whose values lie in
 * [0, range); count holds range + 1 entries of scratch. */
static void sort_terms_by( const amg_term* in, amg_term* out, int32_t n, term_key key, int32_t range, int32_t* count )
{
	memset( count, 0, sizeof( int32_t ) * ( (size_t) range + 1 ) );
	for ( int32_t k = 0; k < n; ++k )
	{
		count[key_of( &in[k], key ) + 1] += 1;
	}
	for ( int32_t v = 0; v < range; ++v )
	{
		count[v + 1] += count[v];
	}
	for ( int32_t k = 0; k < n; ++k )
	{
		out[count[key_of( &in[k], key )]++] = in[k];
	}
}

/* Level L's links to the next one (the sgs level next, or the dense level of c->rows rows when
 * next is NULL): its positions' aggregates, the members of each, and the Galerkin sums. */
static sere_status link_levels( amg_level* L, const sere_csr* a, const int32_t* agg, const int32_t* target,
								const sere_csr* c, const sere_sgs* next )
{
	const sere_sgs* g = L->g;
	const int32_t count = c->rows, next_np = next != NULL ? next->chunks * LANES : count;
	/* the targets are next's value slots (L, U, then the diagonal per position), or the dense
	 * level's entries */
	const int32_t target_range = next != NULL ? next->upper_ptr[next->chunks] + next_np : count * count;
	const int32_t key_range = target_range > a->rows ? target_range : a->rows;
	int32_t* position = malloc( sizeof( int32_t ) * (size_t) count );
	int32_t* tally = malloc( sizeof( int32_t ) * ( (size_t) key_range + 1 ) );
	amg_term* terms = malloc( sizeof( amg_term ) * (size_t) a->nnz );
	amg_term* sorted = malloc( sizeof( amg_term ) * (size_t) a->nnz );
	L->coarse_at = sere_alloc( sizeof( int32_t ) * (size_t) L->np );
	L->member_ptr = sere_alloc( sizeof( int32_t ) * ( (size_t) next_np + 1 ) );
	L->member = sere_alloc( sizeof( int32_t ) * (size_t) a->rows );
	L->sum_ptr = sere_alloc( sizeof( int32_t ) * ( (size_t) a->nnz + 1 ) );
	L->sum_to = sere_alloc( sizeof( int32_t ) * (size_t) a->nnz );
	L->sum_from = sere_alloc( sizeof( int32_t ) * (size_t) a->nnz );
	if ( position == NULL || tally == NULL || terms == NULL || sorted == NULL || L->coarse_at == NULL ||
		 L->member_ptr == NULL || L->member == NULL || L->sum_ptr == NULL || L->sum_to == NULL || L->sum_from == NULL )
	{
		free( position ), free( tally ), free( terms ), free( sorted );
		return SERE_ERR_MEMORY;
	}
	for ( int32_t at = 0; at < next_np; ++at )
	{
		if ( next == NULL || next->row[at] >= 0 )
		{
			position[next != NULL ? next->row[at] : at] = at;
		}
	}
	memset( L->member_ptr, 0, sizeof( int32_t ) * ( (size_t) next_np + 1 ) );
	for ( int32_t at = 0; at < L->np; ++at )
	{
		L->coarse_at[at] = g->row[at] >= 0 ? position[agg[g->row[at]]] : -1;
		L->member_ptr[L->coarse_at[at] + 1] += L->coarse_at[at] >= 0;
	}
	for ( int32_t at = 0; at < next_np; ++at )
	{
		L->member_ptr[at + 1] += L->member_ptr[at];
	}
	for ( int32_t at = 0; at < L->np; ++at ) /* positions ascending within each aggregate */
	{
		if ( L->coarse_at[at] >= 0 )
		{
			L->member[L->member_ptr[L->coarse_at[at]]++] = at;
		}
	}
	for ( int32_t at = next_np; at > 0; --at )
	{
		L->member_ptr[at] = L->member_ptr[at - 1];
	}
	L->member_ptr[0] = 0;
	for ( int32_t i = 0; i < a->rows; ++i )
	{
		for ( int32_t k = a->row_ptr[i]; k < a->row_ptr[i + 1]; ++k )
		{
			int32_t j = a->col[k];
			terms[k] = ( amg_term ){
				.target = next != NULL ? next->slot[target[k]] : agg[i] * count + agg[j],
				.low = i < j ? i : j,
				.high = i < j ? j : i,
				.row = i,
				.source = g->slot[k],
			};
		}
	}
	/* By (target, low, high, row): the terms come in row order, so stable counting sorts by
	 * high, then low, then target order them fully, in linear time. A comparison sort of the
	 * plane tree's 35 000 triangle-layer terms was most of the 6.7 ms its levels took to build
	 * at the first frame; they now take 2.1 ms. */
	const int32_t nnz = a->nnz;
	sort_terms_by( terms, sorted, nnz, KEY_HIGH, a->rows, tally );
	sort_terms_by( sorted, terms, nnz, KEY_LOW, a->rows, tally );
	sort_terms_by( terms, sorted, nnz, KEY_TARGET, target_range, tally );
	L->targets = 0;
	for ( int32_t k = 0; k < nnz; ++k )
	{
		if ( k == 0 || sorted[k].target != sorted[k - 1].target )
		{
			L->sum_ptr[L->targets] = k;
			L->sum_to[L->targets++] = sorted[k].target;
		}
		L->sum_from[k] = sorted[k].source;
	}
	L->sum_ptr[L->targets] = nnz;
	free( position ), free( tally ), free( terms ), free( sorted );
	return SERE_OK;
}

static sere_status level_vectors( amg_level* L )
{
	size_t bytes = sizeof( double ) * (size_t) L->np;
	L->x = sere_alloc( bytes ), L->b = sere_alloc( bytes ), L->r = sere_alloc( bytes );
	L->inv_diag = sere_alloc( bytes );
	if ( L->x == NULL || L->b == NULL || L->r == NULL || L->inv_diag == NULL )
	{
		return SERE_ERR_MEMORY;
	}
	memset( L->x, 0, bytes ), memset( L->b, 0, bytes ), memset( L->r, 0, bytes ), memset( L->inv_diag, 0, bytes );
	return SERE_OK;
}

static void free_csr( sere_csr* c )
{
	sere_free( c->row_ptr ), sere_free( c->col ), sere_free( c->val );
	*c = ( sere_csr ){ 0 };
}

/* Level l over cur (its layout already in m->level[l].g): aggregates, and the next level if
 * coarsening pays. *next_csr gets the next sgs level's matrix (empty when there is none). */
static sere_status coarsen( sere_amg* m, int32_t l, const sere_csr* cur, sere_csr* next_csr )
{
	amg_level* L = &m->level[l];
	sere_status status = level_vectors( L );
	const size_t n = (size_t) cur->rows;
	int32_t *agg = malloc( sizeof( int32_t ) * n ), *pick = malloc( sizeof( int32_t ) * n );
	int32_t* target = malloc( sizeof( int32_t ) * (size_t) ( cur->nnz > 0 ? cur->nnz : 1 ) );
	if ( status != SERE_OK || agg == NULL || pick == NULL || target == NULL )
	{
		free( agg ), free( pick ), free( target );
		return SERE_ERR_MEMORY;
	}
	sere_csr c = { 0 };
	int32_t count = aggregate( cur, agg, pick );
	/* pick is free after aggregate(); coarse_pattern's mark and list need count ≤ n entries each */
	int32_t* list = malloc( sizeof( int32_t ) * n );
	if ( list == NULL )
	{
		status = SERE_ERR_MEMORY;
	}
	else if ( 5 * (int64_t) count <= 4 * (int64_t) cur->rows && l + 1 < SERE_AMG_MAX_LEVELS )
	{
		status = coarse_pattern( cur, agg, count, &c, target, pick, list );
		sere_sgs* next = NULL;
		if ( status == SERE_OK && count > SERE_AMG_DENSE_ROWS )
		{
			status = sere_sgs_create( &c, &next );
		}
		if ( status == SERE_OK )
		{
			status = link_levels( L, cur, agg, target, &c, next );
		}
		if ( status == SERE_OK && next != NULL )
		{
			m->level[l + 1].own = next;
			m->level[l + 1].g = next;
			m->level[l + 1].np = next->chunks * LANES;
			m->levels = l + 2;
			*next_csr = c;
			c = ( sere_csr ){ 0 };
		}
		else if ( status == SERE_OK )
		{
			m->dense_rows = count;
			size_t bytes = sizeof( double ) * (size_t) count;
			m->dense = sere_alloc( bytes * (size_t) count ), m->factor = sere_alloc( bytes * (size_t) count );
			m->dense_b = sere_alloc( bytes ), m->dense_x = sere_alloc( bytes );
			status = m->dense && m->factor && m->dense_b && m->dense_x ? SERE_OK : SERE_ERR_MEMORY;
			if ( status == SERE_OK )
			{
				memset( m->dense, 0, bytes * (size_t) count );
			}
		}
		else
		{
			sere_sgs_destroy( next );
		}
		/* A level past SERE_SGS_MAX_COLORS colors cannot be swept: this level is then the last. */
		status = status == SERE_ERR_ARGUMENT ? SERE_OK : status;
	}
	free_csr( &c );
	free( agg ), free( pick ), free( target ), free( list );
	return status;
}

sere_status sere_amg_create( const sere_csr* a, const sere_sgs* fine, sere_amg** out )
{
	if ( a == NULL || fine == NULL || out == NULL || a->rows <= 0 || a->rows != fine->rows || a->nnz != fine->nnz ||
		 a->row_ptr == NULL || a->row_ptr[0] != 0 || a->row_ptr[a->rows] != a->nnz || !csr_indices_valid( a ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	sere_amg* m = calloc( 1, sizeof( *m ) );
	if ( m == NULL )
	{
		return SERE_ERR_MEMORY;
	}
	m->barrier = sere_alloc( sizeof( sere_spin_barrier ) );
	if ( m->barrier == NULL )
	{
		sere_amg_destroy( m );
		return SERE_ERR_MEMORY;
	}
	memset( m->barrier, 0, sizeof( sere_spin_barrier ) );
	m->level[0].g = fine;
	m->level[0].np = fine->chunks * LANES;
	m->levels = 1;
	sere_csr cur = *a, next = { 0 };
	sere_status status = SERE_OK;
	/* Each level's matrix lives until the next one is built from it (the caller's a is level 0's);
	 * the last call builds none, so nothing is left to free after the loop. */
	for ( int32_t l = 0; status == SERE_OK && l < m->levels; ++l )
	{
		status = coarsen( m, l, &cur, &next );
		if ( l > 0 )
		{
			free_csr( &cur );
		}
		cur = next;
		next = ( sere_csr ){ 0 };
	}
	if ( status != SERE_OK )
	{
		sere_amg_destroy( m );
		return status;
	}
	*out = m;
	return SERE_OK;
}

/* Cholesky factor (lower, row-major) of the dense level; 0 when it is not positive definite. */
static int factor_dense( sere_amg* m )
{
	const int32_t n = m->dense_rows;
	const double* a = m->dense;
	double* f = m->factor;
	for ( int32_t j = 0; j < n; ++j )
	{
		double d = a[j * n + j];
		for ( int32_t k = 0; k < j; ++k )
		{
			d -= f[j * n + k] * f[j * n + k];
		}
		if ( !( d > 0.0 ) || !isfinite( d ) )
		{
			return 0;
		}
		f[j * n + j] = sqrt( d );
		for ( int32_t i = j + 1; i < n; ++i )
		{
			double s = a[i * n + j];
			for ( int32_t k = 0; k < j; ++k )
			{
				s -= f[i * n + k] * f[j * n + k];
			}
			f[i * n + j] = s / f[j * n + j];
		}
	}
	return 1;
}

static void solve_dense( const sere_amg* m, const double* b, double* x )
{
	const int32_t n = m->dense_rows;
	const double* f = m->factor;
	for ( int32_t i = 0; i < n; ++i )
	{
		double s = b[i];
		for ( int32_t k = 0; k < i; ++k )
		{
			s -= f[i * n + k] * x[k];
		}
		x[i] = s / f[i * n + i];
	}
	for ( int32_t i = n - 1; i >= 0; --i )
	{
		double s = x[i];
		for ( int32_t k = i + 1; k < n; ++k )
		{
			s -= f[k * n + i] * x[k];
		}
		x[i] = s / f[i * n + i];
	}
}

sere_status sere_amg_update( sere_amg* m )
{
	if ( m == NULL )
	{
		return SERE_ERR_ARGUMENT;
	}
	m->updated = 1;
	m->stale = 1;
	return SERE_OK;
}

/* amg_shared.h */
sere_status sere_amg_refresh( sere_amg* m, int32_t threads )
{
	if ( !m->updated )
	{
		return SERE_ERR_ARGUMENT;
	}
	int bad = 0;
	const int32_t levels = m->stale ? m->levels : 1;
	for ( int32_t l = 0; l < levels; ++l )
	{
		amg_level* L = &m->level[l];
		const double* val = L->g->val;
		const double* diagonal = val + L->g->upper_ptr[L->g->chunks];
		double* next = l + 1 < m->levels ? m->level[l + 1].own->val : m->dense;
		const int32_t targets = m->stale ? L->targets : 0;
#pragma omp parallel num_threads( sere_team_for( threads ) )
		{
#pragma omp for schedule( static ) reduction( | : bad )
			for ( int32_t at = 0; at < L->np; ++at )
			{
				bool real = L->g->row[at] >= 0;
				bad |= real && !( diagonal[at] > 0.0 && isfinite( diagonal[at] ) );
				L->inv_diag[at] = real && diagonal[at] > 0.0 ? 1.0 / diagonal[at] : 0.0;
			}
#pragma omp for schedule( static )
			for ( int32_t t = 0; t < targets; ++t )
			{
				double sum = 0.0;
				for ( int32_t q = L->sum_ptr[t]; q < L->sum_ptr[t + 1]; ++q )
				{
					sum += val[L->sum_from[q]];
				}
				next[L->sum_to[t]] = sum;
			}
		}
	}
	if ( m->stale )
	{
		m->coarse_bad = bad || ( m->dense_rows > 0 && !factor_dense( m ) );
		m->stale = 0;
	}
	return bad || m->coarse_bad ? SERE_ERR_NOT_SPD : SERE_OK;
}

/* Chunk ch of the backward sweep: out_i = (in_i − Σ_{j≠i} a_ij out_j) / d_i, the full row (a
 * Gauss–Seidel step from the current out, not from zero). */
static inline void full_sweep_chunk( const sere_sgs* g, int32_t ch, const double* inv_diag, const double* in,
									 double* out )
{
	lanes_t lo, up, v = load_lanes( in + ch * LANES ), inv = load_lanes( inv_diag + ch * LANES );
	chunk_sum( g->col, g->val, g->lower_ptr[ch], g->lower_ptr[ch + 1], out, &lo );
	chunk_sum( g->col, g->val, g->upper_ptr[ch], g->upper_ptr[ch + 1], out, &up );
	v.lo = ( v.lo - ( lo.lo + up.lo ) ) * inv.lo;
	v.hi = ( v.hi - ( lo.hi + up.hi ) ) * inv.hi;
	store_lanes( out + ch * LANES, &v );
}

/* r = −U x for chunk ch: the residual b − A x of the forward sweep's x, whose L̃ x is b. */
static inline void upper_residual_chunk( const sere_sgs* g, int32_t ch, const double* x, double* r )
{
	lanes_t up;
	chunk_sum( g->col, g->val, g->upper_ptr[ch], g->upper_ptr[ch + 1], x, &up );
	up.lo = -up.lo;
	up.hi = -up.hi;
	store_lanes( r + ch * LANES, &up );
}

/* The dense level's floor: the two triangular solves read the factor twice; adds in place of theirs. */
static void dense_touch( const sere_amg* m, const double* b, double* x )
{
	const int32_t n = m->dense_rows;
	for ( int32_t pass = 0; pass < 2; ++pass )
	{
		for ( int32_t i = 0; i < n; ++i )
		{
			double sum = b[i];
			for ( int32_t k = 0; k < n; ++k )
			{
				sum += m->factor[i * n + k];
			}
			x[i] = sum;
		}
	}
}

void sere_amg_cycle( const sere_amg* m, int32_t l, const double* b, double* x, amg_team t, bool touch )
{
	const amg_level* L = &m->level[l];
	if ( t.team > 1 && L->np < AMG_SHARED_POSITIONS )
	{
		if ( t.tid == 0 )
		{
			sere_amg_cycle( m, l, b, x, ( amg_team ){ 0, 1, t.barrier }, touch );
		}
		sere_spin_barrier_wait( t.barrier, t.team );
		return;
	}
	const sere_sgs* g = L->g;
	const bool coarse = l + 1 < m->levels || m->dense_rows > 0;
	int32_t first, last;
	/* Forward sweep from zero: x = L̃⁻¹ b, color by color. */
	for ( int32_t c = 0; c < g->colors; ++c )
	{
		sere_team_share( g->color_chunk[c], g->color_chunk[c + 1], t.tid, t.team, &first, &last );
		for ( int32_t ch = first; ch < last; ++ch )
		{
			touch ? sweep_touch( g, false, ch, L->inv_diag, b, x )
				  : sweep_chunk( g, g->lower_ptr, ch, L->inv_diag, b, x, NULL );
		}
		sere_spin_barrier_wait( t.barrier, t.team );
	}
	if ( coarse )
	{
		/* By the sweeps' shares of the colors, as the passes below: each thread meets the x its
		 * own sweep wrote (blocks_of_thread). */
		for ( int32_t c = 0; c < g->colors; ++c )
		{
			sere_team_share( g->color_chunk[c], g->color_chunk[c + 1], t.tid, t.team, &first, &last );
			for ( int32_t ch = first; ch < last; ++ch )
			{
				if ( touch )
				{
					lanes_t up;
					chunk_touch( g->col, g->val, g->upper_ptr[ch], g->upper_ptr[ch + 1], x, &up );
					store_lanes( L->r + ch * LANES, &up );
				}
				else
				{
					upper_residual_chunk( g, ch, x, L->r );
				}
			}
		}
		sere_spin_barrier_wait( t.barrier, t.team );
		const bool dense = l + 1 == m->levels;
		double* bc = dense ? m->dense_b : m->level[l + 1].b;
		double* xc = dense ? m->dense_x : m->level[l + 1].x;
		amg_restrict( m, l, bc, t );
		if ( dense )
		{
			if ( t.tid == 0 )
			{
				touch ? dense_touch( m, bc, xc ) : solve_dense( m, bc, xc );
			}
			sere_spin_barrier_wait( t.barrier, t.team );
		}
		else
		{
			sere_amg_cycle( m, l + 1, bc, xc, t, touch );
		}
		/* Prolongation, scaled: x += ω P x_c (the floor multiplies by one). */
		const double omega = touch ? 1.0 : SERE_AMG_OVERCORRECT;
		for ( int32_t c = 0; c < g->colors; ++c )
		{
			sere_team_share( g->color_chunk[c], g->color_chunk[c + 1], t.tid, t.team, &first, &last );
			for ( int32_t at = first * LANES; at < last * LANES; ++at )
			{
				if ( L->coarse_at[at] >= 0 )
				{
					x[at] += omega * xc[L->coarse_at[at]];
				}
			}
		}
		sere_spin_barrier_wait( t.barrier, t.team );
	}
	/* Backward sweep, the forward one's adjoint: colors in reverse, full rows. */
	for ( int32_t c = g->colors - 1; c >= 0; --c )
	{
		sere_team_share( g->color_chunk[c], g->color_chunk[c + 1], t.tid, t.team, &first, &last );
		for ( int32_t ch = first; ch < last; ++ch )
		{
			touch ? sweep_touch( g, true, ch, L->inv_diag, b, x ) : full_sweep_chunk( g, ch, L->inv_diag, b, x );
		}
		sere_spin_barrier_wait( t.barrier, t.team );
	}
}

sere_status sere_amg_apply( sere_amg* m, const double* r, double* z )
{
	if ( m == NULL || r == NULL || z == NULL )
	{
		return SERE_ERR_ARGUMENT;
	}
	sere_status status = sere_amg_refresh( m, m->threads );
	if ( status != SERE_OK )
	{
		return status;
	}
	amg_level* L = &m->level[0];
	for ( int32_t at = 0; at < L->np; ++at )
	{
		L->b[at] = L->g->row[at] >= 0 ? r[L->g->row[at]] : 0.0;
	}
#pragma omp parallel num_threads( sere_team_for( m->threads ) )
	{
		sere_amg_cycle( m, 0, L->b, L->x, ( amg_team ){ omp_get_thread_num(), omp_get_num_threads(), m->barrier },
						false );
	}
	positions_to_rows( L->g->row, L->np, L->x, z, m->threads );
	return SERE_OK;
}

int32_t sere_amg_levels( const sere_amg* m )
{
	return m == NULL ? 0 : m->levels + ( m->dense_rows > 0 );
}

int32_t sere_amg_rows( const sere_amg* m, int32_t level )
{
	if ( m == NULL )
	{
		return 0;
	}
	if ( level >= 0 && level < m->levels )
	{
		return m->level[level].g->rows;
	}
	return level == m->levels ? m->dense_rows : 0;
}

sere_status sere_amg_set_threads( sere_amg* m, int32_t threads )
{
	return m == NULL ? SERE_ERR_ARGUMENT : sere_threads_store( &m->threads, threads );
}

/* At most `chunk` PCG steps in one parallel region, until ||r|| ≤ target. Per step: z = B r
 * (the V-cycle), γ = rᵀz, p = z + β p, q = A p, α = γ / pᵀq, x += α p, r −= α q; each sum over
 * fixed blocks in block order, so every thread takes the same decisions. */
static void amg_round( cg_state* st, sere_cg_workspace* ws, const sere_amg* m, double target, int32_t max_iterations,
					   int32_t chunk )
{
	const sere_sgs* g = m->level[0].g;
	const int32_t np = m->level[0].np;
	const int32_t blocks = ( np + SERE_CG_BLOCK - 1 ) / SERE_CG_BLOCK;
	double *x = ws->x, *r = ws->r, *z = ws->z, *p = ws->p, *q = ws->w, *partial = ws->partial;
#pragma omp parallel num_threads( sere_team_for( ws->threads ) )
	{
		const amg_team t = { omp_get_thread_num(), omp_get_num_threads(), ws->barrier };
		const owned_blocks own = blocks_of_thread( g, t.tid, t.team );
		cg_state my = *st;
		const int32_t round_end = max_iterations - my.it > chunk ? my.it + chunk : max_iterations;
		while ( my.it < round_end )
		{
			sere_amg_cycle( m, 0, r, z, t, false );
			for ( int32_t blk = owned_block_next( &own, -1 ); blk >= 0; blk = owned_block_next( &own, blk ) )
			{
				partial[4 * blk + 2] = dot_lanes( r, z, blk * SERE_CG_BLOCK, block_end( blk, np ) );
			}
			sere_spin_barrier_wait( ws->barrier, t.team );
			const double gamma = sere_block_sum( partial, blocks, 2 );
			const double beta = my.it == 0 ? 0.0 : gamma / my.gamma_prev;
			for ( int32_t blk = owned_block_next( &own, -1 ); blk >= 0; blk = owned_block_next( &own, blk ) )
			{
				for ( int32_t i = blk * SERE_CG_BLOCK; i < block_end( blk, np ); ++i )
				{
					p[i] = my.it == 0 ? z[i] : z[i] + beta * p[i];
				}
			}
			sere_spin_barrier_wait( ws->barrier, t.team );
			for ( int32_t blk = owned_block_next( &own, -1 ); blk >= 0; blk = owned_block_next( &own, blk ) )
			{
				int32_t chunk_end =
					( blk + 1 ) * CHUNKS_PER_BLOCK < g->chunks ? ( blk + 1 ) * CHUNKS_PER_BLOCK : g->chunks;
				for ( int32_t ch = blk * CHUNKS_PER_BLOCK; ch < chunk_end; ++ch )
				{
					sgs_chunk_product( g, ch, p, NULL, q );
				}
				partial[4 * blk + 1] = dot_lanes( p, q, blk * SERE_CG_BLOCK, block_end( blk, np ) );
			}
			sere_spin_barrier_wait( ws->barrier, t.team );
			double alpha;
			my.status = cg_step_length( sere_block_sum( partial, blocks, 1 ), gamma, &alpha );
			if ( my.status != SERE_OK )
			{
				my.done = 1;
				break;
			}
			for ( int32_t blk = owned_block_next( &own, -1 ); blk >= 0; blk = owned_block_next( &own, blk ) )
			{
				for ( int32_t i = blk * SERE_CG_BLOCK; i < block_end( blk, np ); ++i )
				{
					x[i] += alpha * p[i];
					r[i] -= alpha * q[i];
				}
				partial[4 * blk] = dot_lanes( r, r, blk * SERE_CG_BLOCK, block_end( blk, np ) );
			}
			sere_spin_barrier_wait( ws->barrier, t.team );
			my.gamma_prev = gamma;
			if ( cg_step_done( &my, sere_block_sum( partial, blocks, 0 ), target, max_iterations ) )
			{
				break;
			}
		}
#pragma omp master
		*st = my;
	}
}

sere_status sere_cg_solve_amg( sere_cg_workspace* ws, sere_amg* m, const double* b_in, double* x_in, double tolerance,
							   int32_t max_iterations, sere_cg_result* result )
{
	if ( result == NULL )
	{
		return SERE_ERR_ARGUMENT;
	}
	result->iterations = 0;
	result->residual = 0.0;
	if ( ws == NULL || m == NULL || b_in == NULL || x_in == NULL || m->level[0].g->rows > ws->capacity ||
		 m->level[0].np > ws->positions || !( tolerance >= 0.0 ) || max_iterations < 0 )
	{
		return SERE_ERR_ARGUMENT;
	}
	if ( !m->updated )
	{
		return SERE_ERR_ARGUMENT;
	}
	const sere_sgs* g = m->level[0].g;
	const int32_t np = m->level[0].np;
	const int32_t blocks = ( np + SERE_CG_BLOCK - 1 ) / SERE_CG_BLOCK;
	double *x = ws->x, *b = ws->b, *r = ws->r, *partial = ws->partial;
	int nonfinite = 0;
#pragma omp parallel for num_threads( sere_team_for( ws->threads ) ) schedule( static ) reduction( | : nonfinite )
	for ( int32_t at = 0; at < np; ++at )
	{
		nonfinite |= load_position( g->row[at], b_in, x_in, b, x, at );
	}
	if ( nonfinite )
	{
		return SERE_ERR_NONFINITE;
	}
	const double b_norm = sqrt( dot_lanes( b, b, 0, np ) );
	if ( b_norm == 0.0 )
	{
		for ( int32_t i = 0; i < g->rows; ++i )
		{
			x_in[i] = 0.0;
		}
		return SERE_OK;
	}
	cg_state st = { 0 };
	const int64_t entries = g->upper_ptr[g->chunks] + np;
	const int32_t chunk = (int32_t) ( ( 1 << 24 ) / entries > 16 ? ( 1 << 24 ) / entries : 16 );
	for ( int pass = 0;; ++pass )
	{
		/* The true residual: where the steps start, and after them the one reported. */
#pragma omp parallel num_threads( sere_team_for( ws->threads ) )
		{
			int32_t first, last;
			sere_team_share( 0, blocks, omp_get_thread_num(), omp_get_num_threads(), &first, &last );
			sgs_residual_blocks( g, first, last, np, b, x, NULL, r, partial );
		}
		result->residual = sqrt( sere_block_sum( partial, blocks, 0 ) ) / b_norm;
		if ( pass == 1 || !( result->residual > tolerance ) || max_iterations == 0 )
		{
			break;
		}
		sere_status status = sere_amg_refresh( m, ws->threads );
		if ( status != SERE_OK )
		{
			positions_to_rows( g->row, np, x, x_in, ws->threads );
			return status;
		}
		while ( !st.done && st.it < max_iterations )
		{
			amg_round( &st, ws, m, tolerance * b_norm, max_iterations, chunk );
		}
	}
	positions_to_rows( g->row, np, x, x_in, ws->threads );
	result->iterations = st.it;
	if ( !isfinite( result->residual ) )
	{
		return SERE_ERR_NONFINITE;
	}
	if ( st.status != SERE_OK )
	{
		return (sere_status) st.status;
	}
	return result->residual <= tolerance || st.met ? SERE_OK : SERE_ERR_NO_CONVERGE;
}
