/* sere — the floor of the multigrid PCG (sere_cg_touch_amg, cg.h): its passes with adds only.
 * _GNU_SOURCE: sched_getaffinity for internal/team.h. */
#define _GNU_SOURCE

#include "solve/internal/amg_shared.h"

/* The floor's chunk_sum: the same value loads and gathers, an add where it multiplies and adds. */
static inline void chunk_touch( const int32_t* col, const double* val, int32_t begin, int32_t end, const double* x,
								lanes_t* out )
{
	half_t lo = { 0.0 }, hi = { 0.0 }, xlo, xhi;
	for ( int32_t s = begin; s < end; s += LANES )
	{
		gather( &xlo, x, col + s );
		gather( &xhi, x, col + s + 4 );
		lo += *(const half_t*) ( val + s ) + xlo;
		hi += *(const half_t*) ( val + s + 4 ) + xhi;
	}
	out->lo = lo;
	out->hi = hi;
}

/* The floor of chunk ch of a sweep (ptr: the lower rows, or NULL for full rows): in, D⁻¹ and the
 * row's entries read, out stored, adds only. */
static inline void sweep_touch( const sere_sgs* g, const int32_t* ptr, int32_t ch, const double* inv_diag,
								const double* in, double* out )
{
	lanes_t lo, up = { { 0.0 }, { 0.0 } }, v = load_lanes( in + ch * LANES ), inv = load_lanes( inv_diag + ch * LANES );
	chunk_touch( g->col, g->val, g->lower_ptr[ch], g->lower_ptr[ch + 1], out, &lo );
	if ( ptr == NULL )
	{
		chunk_touch( g->col, g->val, g->upper_ptr[ch], g->upper_ptr[ch + 1], out, &up );
	}
	v.lo = v.lo + lo.lo + up.lo + inv.lo;
	v.hi = v.hi + lo.hi + up.hi + inv.hi;
	store_lanes( out + ch * LANES, &v );
}

/* cycle's floor: the same passes over the same arrays, at the same barriers, with adds. */
static void cycle_touch( const sere_amg* m, int32_t l, const double* b, double* x, amg_team t )
{
	const amg_level* L = &m->level[l];
	if ( t.team > 1 && L->np < AMG_SHARED_POSITIONS )
	{
		if ( t.tid == 0 )
		{
			cycle_touch( m, l, b, x, ( amg_team ){ 0, 1, t.barrier } );
		}
		sere_spin_barrier_wait( t.barrier, t.team );
		return;
	}
	const sere_sgs* g = L->g;
	int32_t first, last;
	for ( int32_t c = 0; c < g->colors; ++c )
	{
		sere_team_share( g->color_chunk[c], g->color_chunk[c + 1], t.tid, t.team, &first, &last );
		for ( int32_t ch = first; ch < last; ++ch )
		{
			sweep_touch( g, g->lower_ptr, ch, L->inv_diag, b, x );
		}
		sere_spin_barrier_wait( t.barrier, t.team );
	}
	if ( l + 1 < m->levels || m->dense_rows > 0 )
	{
		sere_team_share( 0, g->chunks, t.tid, t.team, &first, &last );
		for ( int32_t ch = first; ch < last; ++ch )
		{
			lanes_t up;
			chunk_touch( g->col, g->val, g->upper_ptr[ch], g->upper_ptr[ch + 1], x, &up );
			store_lanes( L->r + ch * LANES, &up );
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
				/* the two triangular solves read the factor twice; adds in place of theirs */
				const int32_t n = m->dense_rows;
				for ( int32_t pass = 0; pass < 2; ++pass )
				{
					for ( int32_t i = 0; i < n; ++i )
					{
						double sum = bc[i];
						for ( int32_t k = 0; k < n; ++k )
						{
							sum += m->factor[i * n + k];
						}
						xc[i] = sum;
					}
				}
			}
			sere_spin_barrier_wait( t.barrier, t.team );
		}
		else
		{
			cycle_touch( m, l + 1, bc, xc, t );
		}
		sere_team_share( 0, L->np, t.tid, t.team, &first, &last );
		for ( int32_t at = first; at < last; ++at )
		{
			if ( L->coarse_at[at] >= 0 )
			{
				x[at] += xc[L->coarse_at[at]];
			}
		}
		sere_spin_barrier_wait( t.barrier, t.team );
	}
	for ( int32_t c = g->colors - 1; c >= 0; --c )
	{
		sere_team_share( g->color_chunk[c], g->color_chunk[c + 1], t.tid, t.team, &first, &last );
		for ( int32_t ch = first; ch < last; ++ch )
		{
			sweep_touch( g, NULL, ch, L->inv_diag, b, x );
		}
		sere_spin_barrier_wait( t.barrier, t.team );
	}
}

/* The floor's dot_lanes: Σ (u_i + v_i) in the same 8 lanes. */
static inline double dot_touch( const double* u, const double* v, int32_t begin, int32_t end )
{
	half_t lo = { 0.0 }, hi = { 0.0 };
	for ( int32_t i = begin; i < end; i += LANES )
	{
		lo += *(const half_t*) ( u + i ) + *(const half_t*) ( v + i );
		hi += *(const half_t*) ( u + i + 4 ) + *(const half_t*) ( v + i + 4 );
	}
	return ( ( lo[0] + lo[1] ) + ( lo[2] + lo[3] ) ) + ( ( hi[0] + hi[1] ) + ( hi[2] + hi[3] ) );
}

sere_status sere_cg_touch_amg( sere_cg_workspace* ws, sere_amg* m, int32_t iterations )
{
	if ( ws == NULL || m == NULL || iterations < 0 || m->level[0].np > ws->positions || !m->updated )
	{
		return SERE_ERR_ARGUMENT;
	}
	sere_status status = sere_amg_refresh( m, ws->threads );
	if ( status != SERE_OK )
	{
		return status;
	}
	const sere_sgs* g = m->level[0].g;
	const int32_t np = m->level[0].np;
	const int32_t blocks = ( np + SERE_CG_BLOCK - 1 ) / SERE_CG_BLOCK;
	double *x = ws->x, *r = ws->r, *z = ws->z, *p = ws->p, *q = ws->w, *partial = ws->partial;
	/* from zero every call: the adds then stay far from overflow over a solve's iterations */
	double* vectors[5] = { x, r, z, p, q };
	for ( int v = 0; v < 5; ++v )
	{
		memset( vectors[v], 0, sizeof( double ) * (size_t) np );
	}
#pragma omp parallel num_threads( sere_team_for( ws->threads ) )
	{
		const amg_team t = { omp_get_thread_num(), omp_get_num_threads(), ws->barrier };
		int32_t blk_first, blk_last;
		sere_team_share( 0, blocks, t.tid, t.team, &blk_first, &blk_last );
		for ( int32_t it = 0; it < iterations; ++it )
		{
			cycle_touch( m, 0, r, z, t );
			for ( int32_t blk = blk_first; blk < blk_last; ++blk )
			{
				partial[4 * blk + 2] = dot_touch( r, z, blk * SERE_CG_BLOCK, block_end( blk, np ) );
			}
			sere_spin_barrier_wait( ws->barrier, t.team );
			for ( int32_t blk = blk_first; blk < blk_last; ++blk )
			{
				for ( int32_t i = blk * SERE_CG_BLOCK; i < block_end( blk, np ); ++i )
				{
					p[i] = z[i] + p[i];
				}
			}
			sere_spin_barrier_wait( ws->barrier, t.team );
			for ( int32_t blk = blk_first; blk < blk_last; ++blk )
			{
				int32_t chunk_end =
					( blk + 1 ) * CHUNKS_PER_BLOCK < g->chunks ? ( blk + 1 ) * CHUNKS_PER_BLOCK : g->chunks;
				for ( int32_t ch = blk * CHUNKS_PER_BLOCK; ch < chunk_end; ++ch )
				{
					sweep_touch( g, NULL, ch, g->val + g->upper_ptr[g->chunks], p, q );
				}
				partial[4 * blk + 1] = dot_touch( p, q, blk * SERE_CG_BLOCK, block_end( blk, np ) );
			}
			sere_spin_barrier_wait( ws->barrier, t.team );
			for ( int32_t blk = blk_first; blk < blk_last; ++blk )
			{
				for ( int32_t i = blk * SERE_CG_BLOCK; i < block_end( blk, np ); ++i )
				{
					x[i] += p[i];
					r[i] += q[i];
				}
				partial[4 * blk] = dot_touch( r, r, blk * SERE_CG_BLOCK, block_end( blk, np ) );
			}
			sere_spin_barrier_wait( ws->barrier, t.team );
		}
	}
	return SERE_OK;
}
