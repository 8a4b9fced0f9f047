#include "ref/pbd_ref.h"

#include <math.h>

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
