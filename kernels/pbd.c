#include "pbd.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

struct sere_pbd
{
	int32_t count, particle_count;
	sere_coloring coloring;
	int32_t *a, *b; /* in color order */
	float* rest;
	float* lambda; /* XPBD multipliers */
	/* Jacobi: particle i's constraints (color-order indices) in [adjacency_offset[i], [i+1]) */
	int32_t* adjacency_offset;
	int32_t* adjacency;
	float *jx, *jy, *jz; /* Jacobi scratch positions */
};

sere_pbd_params sere_pbd_params_default( void )
{
	sere_pbd_params params = {
		.stiffness = 1.0f, .tolerance = 1e-3f, .max_iterations = 200, .compliance = 0.0f, .dt = 0.002f
	};
	return params;
}

void sere_pbd_destroy( sere_pbd* pbd )
{
	if ( pbd == NULL )
	{
		return;
	}
	sere_coloring_destroy( &pbd->coloring );
	sere_free( pbd->a );
	sere_free( pbd->b );
	sere_free( pbd->rest );
	sere_free( pbd->lambda );
	sere_free( pbd->adjacency_offset );
	sere_free( pbd->adjacency );
	sere_free( pbd->jx );
	sere_free( pbd->jy );
	sere_free( pbd->jz );
	free( pbd );
}

const sere_coloring* sere_pbd_coloring( const sere_pbd* pbd )
{
	return &pbd->coloring;
}

sere_status sere_pbd_create( const int32_t* a, const int32_t* b, int32_t count, int32_t particle_count, sere_pbd** out )
{
	sere_pbd* pbd = calloc( 1, sizeof( *pbd ) );
	if ( pbd == NULL )
	{
		return SERE_ERR_MEMORY;
	}
	sere_status status = sere_color_springs( a, b, count, particle_count, &pbd->coloring );
	if ( status != SERE_OK )
	{
		free( pbd );
		return status;
	}
	pbd->count = count;
	pbd->particle_count = particle_count;
	size_t ints = sizeof( int32_t ) * (size_t) sere_pad( count );
	size_t floats = sizeof( float ) * (size_t) sere_pad( particle_count );
	pbd->a = sere_alloc( ints );
	pbd->b = sere_alloc( ints );
	pbd->rest = sere_alloc( sizeof( float ) * (size_t) sere_pad( count ) );
	pbd->lambda = sere_alloc( sizeof( float ) * (size_t) sere_pad( count ) );
	pbd->adjacency_offset = sere_alloc( sizeof( int32_t ) * ( (size_t) particle_count + 1 ) );
	pbd->adjacency = sere_alloc( sizeof( int32_t ) * 2 * (size_t) count );
	pbd->jx = sere_alloc( floats );
	pbd->jy = sere_alloc( floats );
	pbd->jz = sere_alloc( floats );
	if ( !pbd->a || !pbd->b || !pbd->rest || !pbd->lambda || !pbd->adjacency_offset || !pbd->adjacency || !pbd->jx ||
		 !pbd->jy || !pbd->jz )
	{
		sere_pbd_destroy( pbd );
		return SERE_ERR_MEMORY;
	}
	for ( int32_t k = 0; k < count; ++k )
	{
		int32_t s = pbd->coloring.order[k];
		pbd->a[k] = a[s];
		pbd->b[k] = b[s];
		pbd->adjacency_offset[a[s] + 1] += 1;
		pbd->adjacency_offset[b[s] + 1] += 1;
	}
	for ( int32_t i = 0; i < particle_count; ++i )
	{
		pbd->adjacency_offset[i + 1] += pbd->adjacency_offset[i];
	}
	int32_t* fill = malloc( sizeof( int32_t ) * (size_t) particle_count );
	if ( fill == NULL )
	{
		sere_pbd_destroy( pbd );
		return SERE_ERR_MEMORY;
	}
	memcpy( fill, pbd->adjacency_offset, sizeof( int32_t ) * (size_t) particle_count );
	for ( int32_t k = 0; k < count; ++k )
	{
		pbd->adjacency[fill[pbd->a[k]]++] = k;
		pbd->adjacency[fill[pbd->b[k]]++] = k;
	}
	free( fill );
	*out = pbd;
	return SERE_OK;
}

sere_status sere_pbd_set_rest( sere_pbd* pbd, const float* rest )
{
	int bad = 0;
	for ( int32_t k = 0; k < pbd->count; ++k )
	{
		float l = rest[pbd->coloring.order[k]];
		bad |= !( l > 0.0f ) || !isfinite( l );
		pbd->rest[k] = l;
	}
	return bad ? SERE_ERR_GEOMETRY : SERE_OK;
}

void sere_pbd_predict( int32_t count, const float* x, const float* y, const float* z, float* vx, float* vy, float* vz,
					   float* px, float* py, float* pz, const float* inv_m, const float gravity[3], float dt )
{
	const float gx = gravity[0] * dt, gy = gravity[1] * dt, gz = gravity[2] * dt;
#pragma omp parallel for simd schedule( static )
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
#pragma omp parallel for simd schedule( static )
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

static sere_status check_params( const sere_pbd* pbd, const float* px, const float* py, const float* pz,
								 const float* inv_m, const sere_pbd_params* params )
{
	if ( pbd == NULL || px == NULL || py == NULL || pz == NULL || inv_m == NULL || params == NULL ||
		 !( params->stiffness >= 0.0f && params->stiffness <= 1.0f ) || !( params->tolerance > 0.0f ) ||
		 params->max_iterations < 1 || !( params->compliance >= 0.0f ) ||
		 ( params->compliance > 0.0f && !( params->dt > 0.0f ) ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	int bad = 0;
#pragma omp parallel for simd schedule( static ) reduction( | : bad )
	for ( int32_t i = 0; i < pbd->particle_count; ++i )
	{
		bad |= !isfinite( px[i] ) || !isfinite( py[i] ) || !isfinite( pz[i] );
	}
	return bad ? SERE_ERR_NONFINITE : SERE_OK;
}

sere_status sere_pbd_project( sere_pbd* pbd, float* px, float* py, float* pz, const float* inv_m,
							  const sere_pbd_params* params, sere_pbd_report* report )
{
	memset( report, 0, sizeof( *report ) );
	sere_status status = check_params( pbd, px, py, pz, inv_m, params );
	if ( status != SERE_OK )
	{
		return status;
	}
	const int32_t* restrict ca = pbd->a;
	const int32_t* restrict cb = pbd->b;
	const float* restrict rest = pbd->rest;
	float* restrict lambda = pbd->lambda;
	const int32_t colors = pbd->coloring.color_count;
	const int32_t* offsets = pbd->coloring.offsets;
	const float k = params->stiffness, tolerance = params->tolerance;
	const int xpbd = params->compliance > 0.0f;
	const float alpha = xpbd ? params->compliance / ( params->dt * params->dt ) : 0.0f;
	if ( xpbd )
	{
		memset( lambda, 0, sizeof( float ) * (size_t) pbd->count );
	}
	int32_t iterations = 0;
	float worst = 0.0f, after = INFINITY;
	int degenerate = 0;
#pragma omp parallel
	{
		for ( int32_t it = 0; it < params->max_iterations; ++it )
		{
#pragma omp single
			worst = 0.0f;
			for ( int32_t c = 0; c < colors; ++c )
			{
				/* No two constraints of a color share a particle: the gathers and scatters of a
				 * batch are independent, so the batch runs in parallel and in SIMD lanes. */
#pragma omp for simd schedule( static ) reduction( max : worst ) reduction( | : degenerate )
				for ( int32_t q = offsets[c]; q < offsets[c + 1]; ++q )
				{
					int32_t ia = ca[q], ib = cb[q];
					float dx = px[ib] - px[ia], dy = py[ib] - py[ia], dz = pz[ib] - pz[ia];
					float length = sqrtf( dx * dx + dy * dy + dz * dz );
					float wa = inv_m[ia], wb = inv_m[ib];
					float constraint = length - rest[q]; /* Eq. 13 */
					float strain = fabsf( constraint ) / rest[q];
					worst = strain > worst ? strain : worst;
					degenerate |= !( length > 0.0f );
					float wsum = wa + wb;
					float s;
					if ( xpbd )
					{
						float dl = ( -constraint - alpha * lambda[q] ) / ( wsum + alpha );
						lambda[q] += dl;
						s = length > 0.0f ? -dl / length : 0.0f;
					}
					else
					{
						s = ( wsum > 0.0f && length > 0.0f ) ? k * constraint / ( wsum * length ) : 0.0f;
					}
					px[ia] += wa * s * dx;
					py[ia] += wa * s * dy;
					pz[ia] += wa * s * dz;
					px[ib] -= wb * s * dx;
					py[ib] -= wb * s * dy;
					pz[ib] -= wb * s * dz;
				}
			}
			/* Every thread reads the same reduced worst after the last batch's barrier. A sweep
			 * measures each constraint before projecting it, so later batches can undo a little of
			 * the earlier ones: when the sweep says converged, measure the state it left. */
			int stop = degenerate || !( worst == worst );
			if ( !stop && worst < tolerance )
			{
#pragma omp barrier
#pragma omp single
				after = 0.0f;
#pragma omp for simd schedule( static ) reduction( max : after )
				for ( int32_t q = 0; q < pbd->count; ++q )
				{
					int32_t ia = ca[q], ib = cb[q];
					float dx = px[ib] - px[ia], dy = py[ib] - py[ia], dz = pz[ib] - pz[ia];
					float strain = fabsf( sqrtf( dx * dx + dy * dy + dz * dz ) - rest[q] ) / rest[q];
					after = strain > after ? strain : after;
				}
				stop = after < tolerance;
			}
#pragma omp single nowait
			iterations = it + 1;
			if ( stop )
			{
				break;
			}
#pragma omp barrier
		}
	}
	report->iterations = iterations;
	report->max_strain = after < tolerance ? after : worst;
	report->hit_cap = !( after < tolerance );
	if ( degenerate )
	{
		return SERE_ERR_GEOMETRY;
	}
	return isfinite( worst ) ? SERE_OK : SERE_ERR_NONFINITE;
}

sere_status sere_pbd_project_jacobi( sere_pbd* pbd, float* px, float* py, float* pz, const float* inv_m,
									 const sere_pbd_params* params, sere_pbd_report* report )
{
	memset( report, 0, sizeof( *report ) );
	sere_status status = check_params( pbd, px, py, pz, inv_m, params );
	if ( status != SERE_OK )
	{
		return status;
	}
	const int32_t n = pbd->particle_count;
	float *jx = pbd->jx, *jy = pbd->jy, *jz = pbd->jz;
	const float k = params->stiffness;
	float worst = 0.0f;
	int32_t it = 0;
	int degenerate = 0;
	for ( ; it < params->max_iterations; ++it )
	{
		worst = 0.0f;
		/* Every particle gathers its constraints' corrections from the same old positions. */
#pragma omp parallel for schedule( static ) reduction( max : worst ) reduction( | : degenerate )
		for ( int32_t i = 0; i < n; ++i )
		{
			float sx = 0.0f, sy = 0.0f, sz = 0.0f;
			int32_t used = pbd->adjacency_offset[i + 1] - pbd->adjacency_offset[i];
			for ( int32_t e = pbd->adjacency_offset[i]; e < pbd->adjacency_offset[i + 1]; ++e )
			{
				int32_t q = pbd->adjacency[e];
				int32_t other = pbd->a[q] == i ? pbd->b[q] : pbd->a[q];
				float dx = px[other] - px[i], dy = py[other] - py[i], dz = pz[other] - pz[i];
				float length = sqrtf( dx * dx + dy * dy + dz * dz );
				float constraint = length - pbd->rest[q];
				float strain = fabsf( constraint ) / pbd->rest[q];
				worst = strain > worst ? strain : worst;
				degenerate |= !( length > 0.0f );
				float wsum = inv_m[i] + inv_m[other];
				float s = ( wsum > 0.0f && length > 0.0f ) ? k * constraint / ( wsum * length ) : 0.0f;
				sx += inv_m[i] * s * dx;
				sy += inv_m[i] * s * dy;
				sz += inv_m[i] * s * dz;
			}
			float inv_used = used > 0 ? 1.0f / (float) used : 0.0f;
			jx[i] = px[i] + sx * inv_used;
			jy[i] = py[i] + sy * inv_used;
			jz[i] = pz[i] + sz * inv_used;
		}
		memcpy( px, jx, sizeof( float ) * (size_t) n );
		memcpy( py, jy, sizeof( float ) * (size_t) n );
		memcpy( pz, jz, sizeof( float ) * (size_t) n );
		if ( worst < params->tolerance || degenerate || !isfinite( worst ) )
		{
			it += 1;
			break;
		}
	}
	report->iterations = it;
	report->max_strain = worst;
	report->hit_cap = !( worst < params->tolerance );
	if ( degenerate )
	{
		return SERE_ERR_GEOMETRY;
	}
	return isfinite( worst ) ? SERE_OK : SERE_ERR_NONFINITE;
}
