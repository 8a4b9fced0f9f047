#include "ref/pbd_ref.h"

#include <math.h>
#include <stdlib.h>

int32_t sere_pbd_ref_project( sere_ref_particle* particles, const sere_ref_spring* springs, int32_t spring_count,
							  float stiffness, float tolerance, int32_t max_iterations, float* max_strain )
{
	int32_t it = 0;
	float worst = 0.0f;
	while ( it < max_iterations )
	{
		worst = 0.0f;
		for ( int32_t s = 0; s < spring_count; ++s )
		{
			sere_ref_particle* pa = particles + springs[s].a;
			sere_ref_particle* pb = particles + springs[s].b;
			float dx = pb->x - pa->x, dy = pb->y - pa->y, dz = pb->z - pa->z;
			float length = sqrtf( dx * dx + dy * dy + dz * dz );
			float c = length - springs[s].rest; /* Jeong Eq. 13 */
			worst = fmaxf( worst, fabsf( c ) / springs[s].rest );
			float w = pa->inv_m + pb->inv_m;
			if ( w <= 0.0f || length <= 0.0f )
			{
				continue;
			}
			float f = stiffness * c / ( w * length );
			pa->x += pa->inv_m * f * dx;
			pa->y += pa->inv_m * f * dy;
			pa->z += pa->inv_m * f * dz;
			pb->x -= pb->inv_m * f * dx;
			pb->y -= pb->inv_m * f * dy;
			pb->z -= pb->inv_m * f * dz;
		}
		it += 1;
		if ( worst < tolerance )
		{
			break;
		}
	}
	*max_strain = worst;
	return it;
}

int32_t sere_pbd_ref_step_residual( const sere_ref_particle* particles, const sere_ref_particle* predicted,
									int32_t particle_count, const sere_ref_spring* springs, const float* lambda,
									int32_t spring_count, double out[3] )
{
	double* force = calloc( 3 * (size_t) particle_count, sizeof( double ) );
	out[0] = out[1] = out[2] = 0.0;
	if ( force == NULL )
	{
		return -1;
	}
	for ( int32_t s = 0; s < spring_count; ++s )
	{
		const sere_ref_particle* pa = particles + springs[s].a;
		const sere_ref_particle* pb = particles + springs[s].b;
		double dx = (double) pb->x - pa->x, dy = (double) pb->y - pa->y, dz = (double) pb->z - pa->z;
		double length = sqrt( dx * dx + dy * dy + dz * dz );
		if ( length <= 0.0 )
		{
			continue;
		}
		/* ∇_b C = d/|d| = −∇_a C */
		double f = (double) lambda[s] / length;
		force[3 * springs[s].b] += f * dx, force[3 * springs[s].b + 1] += f * dy, force[3 * springs[s].b + 2] += f * dz;
		force[3 * springs[s].a] -= f * dx, force[3 * springs[s].a + 1] -= f * dy, force[3 * springs[s].a + 2] -= f * dz;
	}
	int32_t counted = 0;
	for ( int32_t i = 0; i < particle_count; ++i )
	{
		if ( !( particles[i].inv_m > 0.0f ) )
		{
			continue;
		}
		double m = 1.0 / (double) particles[i].inv_m;
		double inertia[3] = { m * ( (double) particles[i].x - predicted[i].x ),
							  m * ( (double) particles[i].y - predicted[i].y ),
							  m * ( (double) particles[i].z - predicted[i].z ) };
		for ( int k = 0; k < 3; ++k )
		{
			double h = inertia[k] - force[3 * i + k];
			out[0] += h * h;
			out[1] += inertia[k] * inertia[k];
			out[2] += force[3 * i + k] * force[3 * i + k];
		}
		counted += 1;
	}
	free( force );
	out[0] = sqrt( out[0] ), out[1] = sqrt( out[1] ), out[2] = sqrt( out[2] );
	return counted;
}
