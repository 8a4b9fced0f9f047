/* sere — the floor of the multigrid PCG (sere_cg_touch_amg, cg.h): its passes with adds only.
 * _GNU_SOURCE: sched_getaffinity for internal/team.h. */
#define _GNU_SOURCE

#include "solve/internal/amg_shared.h"

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
		const owned_blocks own = blocks_of_thread( g, t.tid, t.team );
		for ( int32_t it = 0; it < iterations; ++it )
		{
			sere_amg_cycle( m, 0, r, z, t, true );
			for ( int32_t blk = owned_block_next( &own, -1 ); blk >= 0; blk = owned_block_next( &own, blk ) )
			{
				partial[4 * blk + 2] = dot_touch( r, z, blk * SERE_CG_BLOCK, block_end( blk, np ) );
			}
			sere_spin_barrier_wait( ws->barrier, t.team );
			for ( int32_t blk = owned_block_next( &own, -1 ); blk >= 0; blk = owned_block_next( &own, blk ) )
			{
				for ( int32_t i = blk * SERE_CG_BLOCK; i < block_end( blk, np ); ++i )
				{
					p[i] = z[i] + p[i];
				}
			}
			sere_spin_barrier_wait( ws->barrier, t.team );
			for ( int32_t blk = owned_block_next( &own, -1 ); blk >= 0; blk = owned_block_next( &own, blk ) )
			{
				int32_t chunk_end =
					( blk + 1 ) * CHUNKS_PER_BLOCK < g->chunks ? ( blk + 1 ) * CHUNKS_PER_BLOCK : g->chunks;
				for ( int32_t ch = blk * CHUNKS_PER_BLOCK; ch < chunk_end; ++ch )
				{
					sweep_touch( g, true, ch, g->val + g->upper_ptr[g->chunks], p, q );
				}
				partial[4 * blk + 1] = dot_touch( p, q, blk * SERE_CG_BLOCK, block_end( blk, np ) );
			}
			sere_spin_barrier_wait( ws->barrier, t.team );
			for ( int32_t blk = owned_block_next( &own, -1 ); blk >= 0; blk = owned_block_next( &own, blk ) )
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
