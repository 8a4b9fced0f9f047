#include "shrink.h"

#include "layers.h"

#include <math.h>

sere_status sere_shrink( const int32_t* a, const int32_t* b, const uint8_t* kind, const float* rest0, float* rest,
						 int32_t first, int32_t count, const double* m, const double* m0,
						 const sere_shrink_params* params )
{
	if ( params == NULL || !( params->alpha > 0.0 ) || !isfinite( params->sigma_vein ) ||
		 !isfinite( params->sigma_surf ) || params->min_length_ratio < 0.0 || count < 0 )
	{
		return SERE_ERR_ARGUMENT;
	}
	const double alpha = params->alpha, m_min = params->m_min, ratio = params->min_length_ratio;
	const double sigma_vein = params->sigma_vein, sigma_surf = params->sigma_surf;
#pragma omp parallel for simd schedule( static )
	for ( int32_t s = first; s < first + count; ++s )
	{
		double ma = m[a[s]], mb = m[b[s]];
		double v_rel = ( ma + mb ) / ( m0[a[s]] + m0[b[s]] ); /* Eq. 11 */
		double loss = v_rel < 1.0 ? 1.0 - v_rel : 0.0;
		double sigma = ( kind[s] & SERE_SPRING_VEIN ) ? sigma_vein : sigma_surf;
		double length = (double) rest0[s] * ( 1.0 - sigma * pow( loss, alpha ) ); /* Eq. 12 */
		int stopped = ma < m_min || mb < m_min || length < ratio * (double) rest0[s];
		rest[s] = stopped ? rest[s] : (float) length;
	}
	return SERE_OK;
}
