/* sere — what an XPBD projection leaves of its step's two conditions besides the one it tests
 * (Macklin et al. 2016, Eqs. 8–9), and its multipliers, read from the workspace after the call.
 * _GNU_SOURCE: sched_getaffinity for internal/team.h. */
#define _GNU_SOURCE

#include "solve/internal/pbd_shared.h"

#include <math.h>

static sere_status check_residual_call( const sere_pbd* pbd )
{
	return pbd != NULL && pbd->multipliers_valid ? SERE_OK : SERE_ERR_ARGUMENT;
}

sere_status sere_pbd_multipliers( const sere_pbd* pbd, float* lambda )
{
	if ( lambda == NULL || check_residual_call( pbd ) != SERE_OK )
	{
		return SERE_ERR_ARGUMENT;
	}
	for ( int32_t q = 0; q < pbd->lanes; ++q )
	{
		if ( pbd->source[q] >= 0 )
		{
			lambda[pbd->source[q]] = pbd->lambda[q];
		}
	}
	return SERE_OK;
}

/* Particle i's three squared norms, added to sum[0..2]: h_i, m_i (x_i − x̃_i) and the multipliers'
 * force Σ λ_q ∇_i C_q, ∇_i C_q = (x_i − x_o)/|x_i − x_o| for either end (Jeong Eq. 13's C is
 * symmetric in its ends). Its constraints are read from the Jacobi adjacency, in lane order. */
static void particle_terms( const sere_pbd* pbd, int32_t s, const float* px, const float* py, const float* pz,
							const float* tx, const float* ty, const float* tz, double m, double sum[3] )
{
	const int32_t i = pbd->particle[s];
	double fx = 0.0, fy = 0.0, fz = 0.0;
	for ( int32_t e = pbd->adjacency_offset[s]; e < pbd->adjacency_offset[s + 1]; ++e )
	{
		const int32_t q = pbd->adjacency[2 * e], o = pbd->particle[pbd->adjacency[2 * e + 1] / 4];
		double dx = (double) px[i] - px[o], dy = (double) py[i] - py[o], dz = (double) pz[i] - pz[o];
		double length = sqrt( dx * dx + dy * dy + dz * dz );
		/* coinciding ends have no gradient; a projection refuses them before it moves anything */
		double scale = length > 0.0 ? (double) pbd->lambda[q] / length : 0.0;
		fx += scale * dx, fy += scale * dy, fz += scale * dz;
	}
	double ix = m * ( (double) px[i] - tx[i] ), iy = m * ( (double) py[i] - ty[i] ),
		   iz = m * ( (double) pz[i] - tz[i] );
	double hx = ix - fx, hy = iy - fy, hz = iz - fz;
	sum[0] += hx * hx + hy * hy + hz * hz;
	sum[1] += ix * ix + iy * iy + iz * iz;
	sum[2] += fx * fx + fy * fy + fz * fz;
}

sere_status sere_pbd_step_residual( const sere_pbd* pbd, const float* px, const float* py, const float* pz,
									const float* tx, const float* ty, const float* tz, const float* inv_m,
									sere_pbd_residuals* out )
{
	if ( px == NULL || py == NULL || pz == NULL || tx == NULL || ty == NULL || tz == NULL || inv_m == NULL ||
		 out == NULL || check_residual_call( pbd ) != SERE_OK )
	{
		return SERE_ERR_ARGUMENT;
	}
	const int32_t n = pbd->particle_count;
	const int32_t blocks = ( n + RESIDUAL_BLOCK - 1 ) / RESIDUAL_BLOCK;
	double* partial = pbd->residual_partial;
#pragma omp parallel for num_threads( sere_team_for( pbd->thread_count ) ) schedule( static )
	for ( int32_t block = 0; block < blocks; ++block )
	{
		double sum[3] = { 0.0, 0.0, 0.0 };
		int32_t counted = 0;
		const int32_t first = block * RESIDUAL_BLOCK, last = n - first < RESIDUAL_BLOCK ? n : first + RESIDUAL_BLOCK;
		for ( int32_t s = first; s < last; ++s )
		{
			const float w = inv_m[pbd->particle[s]];
			if ( w > 0.0f && !( pbd->push[s] > 0.0f ) )
			{
				particle_terms( pbd, s, px, py, pz, tx, ty, tz, 1.0 / (double) w, sum );
				counted += 1;
			}
		}
		partial[4 * block] = sum[0], partial[4 * block + 1] = sum[1], partial[4 * block + 2] = sum[2];
		partial[4 * block + 3] = (double) counted;
	}
	out->primal = sqrt( sere_block_sum( partial, blocks, 0 ) );
	out->inertia = sqrt( sere_block_sum( partial, blocks, 1 ) );
	out->constraint = sqrt( sere_block_sum( partial, blocks, 2 ) );
	out->particles = (int32_t) sere_block_sum( partial, blocks, 3 );
	return SERE_OK;
}
