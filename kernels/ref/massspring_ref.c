#include "ref/massspring_ref.h"

#include <math.h>

/* Forces: gravity, then the springs. */
static void ref_forces( const sere_massspring_topology* topology, const sere_massspring_particles* p,
						const sere_massspring_params* params, float* fx, float* fy, float* fz )
{
	for ( int32_t i = 0; i < p->count; ++i )
	{
		float m = p->inv_m[i] > 0.0f ? 1.0f / p->inv_m[i] : 0.0f;
		fx[i] = m * params->gravity[0];
		fy[i] = m * params->gravity[1];
		fz[i] = m * params->gravity[2];
	}
	const int32_t springs = topology->structural_count + topology->flexion_count;
	for ( int32_t s = 0; s < springs; ++s )
	{
		const int structural = s < topology->structural_count;
		const int32_t a = topology->a[s], b = topology->b[s];
		float dx = p->x[b] - p->x[a], dy = p->y[b] - p->y[a], dz = p->z[b] - p->z[a];
		float len = sqrtf( dx * dx + dy * dy + dz * dz );
		float nx = len > 0.0f ? dx / len : 0.0f;
		float ny = len > 0.0f ? dy / len : 0.0f;
		float nz = len > 0.0f ? dz / len : 0.0f;
		float rest = topology->rest0[s] * ( 1.0f - ( structural ? params->shrink : params->curl ) );
		float k = structural ? params->stiffness : params->bend_stiffness;
		float along = ( p->vx[b] - p->vx[a] ) * nx + ( p->vy[b] - p->vy[a] ) * ny + ( p->vz[b] - p->vz[a] ) * nz;
		float f = k * ( len - rest ) / rest + params->damping * along;
		fx[a] += f * nx;
		fy[a] += f * ny;
		fz[a] += f * nz;
		fx[b] -= f * nx;
		fy[b] -= f * ny;
		fz[b] -= f * nz;
	}
}

/* Tang Eq. 1, explicit Euler for the velocities. */
static void ref_euler( sere_massspring_particles* p, const sere_massspring_params* params, const float* fx,
					   const float* fy, const float* fz )
{
	const float dt = params->dt;
	for ( int32_t i = 0; i < p->count; ++i )
	{
		if ( p->inv_m[i] > 0.0f )
		{
			float m = 1.0f / p->inv_m[i];
			p->vx[i] = ( p->vx[i] + fx[i] / m * dt ) * ( 1.0f - params->drag );
			p->vy[i] = ( p->vy[i] + fy[i] / m * dt ) * ( 1.0f - params->drag );
			p->vz[i] = ( p->vz[i] + fz[i] / m * dt ) * ( 1.0f - params->drag );
		}
		else
		{
			p->vx[i] = 0.0f;
			p->vy[i] = 0.0f;
			p->vz[i] = 0.0f;
		}
	}
}

/* Tang Eq. 2's p for structural spring s: the relative position d of its second end from its
 * first after a step of dt at the current velocities. Returns |p|. */
static float ref_spring_after( const sere_massspring_topology* topology, const sere_massspring_particles* p, int32_t s,
							   float dt, float d[3] )
{
	const int32_t a = topology->a[s], b = topology->b[s];
	d[0] = ( p->x[b] - p->x[a] ) + dt * ( p->vx[b] - p->vx[a] );
	d[1] = ( p->y[b] - p->y[a] ) + dt * ( p->vy[b] - p->vy[a] );
	d[2] = ( p->z[b] - p->z[a] ) + dt * ( p->vz[b] - p->vz[a] );
	return sqrtf( d[0] * d[0] + d[1] * d[1] + d[2] * d[2] );
}

/* One sweep of Tang Eq. 2 over the structural springs: the relative position after the step
 * must stay within τ_c of the natural length, and each violating spring is moved onto the band
 * narrowed by the tolerance δ. Returns the largest correction over the rest length; counts the
 * springs it limited into *limited. */
static float ref_limit_sweep( const sere_massspring_topology* topology, sere_massspring_particles* p,
							  const sere_massspring_params* params, int32_t* limited )
{
	const float dt = params->dt, tau = params->strain_limit, delta = params->strain_tolerance;
	float worst = 0.0f;
	for ( int32_t s = 0; s < topology->structural_count; ++s )
	{
		const int32_t a = topology->a[s], b = topology->b[s];
		float d[3];
		float len = ref_spring_after( topology, p, s, dt, d );
		const float px = d[0], py = d[1], pz = d[2];
		float rest = topology->rest0[s] * ( 1.0f - params->shrink );
		float target = len;
		if ( len > rest * ( 1.0f + tau - delta ) )
		{
			target = rest * ( 1.0f + tau - delta );
		}
		if ( len < rest * ( 1.0f - tau + delta ) )
		{
			target = rest * ( 1.0f - tau + delta );
		}
		if ( target == len )
		{
			continue;
		}
		worst = fmaxf( worst, fabsf( len - target ) / rest );
		++*limited;
		float w = p->inv_m[a] + p->inv_m[b];
		if ( w > 0.0f && len > 0.0f )
		{
			/* Change the relative velocity along p so that |p| becomes the target. */
			float dv = ( len - target ) / len / dt;
			p->vx[a] += p->inv_m[a] / w * dv * px;
			p->vy[a] += p->inv_m[a] / w * dv * py;
			p->vz[a] += p->inv_m[a] / w * dv * pz;
			p->vx[b] -= p->inv_m[b] / w * dv * px;
			p->vy[b] -= p->inv_m[b] / w * dv * py;
			p->vz[b] -= p->inv_m[b] / w * dv * pz;
		}
	}
	return worst;
}

/* True when every structural spring's relative position after the step is inside the true
 * band (1 ± τ_c) of its natural length. */
static int ref_within_band( const sere_massspring_topology* topology, const sere_massspring_particles* p,
							const sere_massspring_params* params )
{
	const float dt = params->dt, tau = params->strain_limit;
	int within = 1;
	for ( int32_t s = 0; s < topology->structural_count; ++s )
	{
		float d[3];
		float ratio = ref_spring_after( topology, p, s, dt, d ) / ( topology->rest0[s] * ( 1.0f - params->shrink ) );
		if ( ratio > 1.0f + tau || ratio < 1.0f - tau )
		{
			within = 0;
		}
	}
	return within;
}

sere_status sere_massspring_ref_step( const sere_massspring_topology* topology, sere_massspring_particles* p,
									  const sere_massspring_params* params, float* fx, float* fy, float* fz,
									  sere_massspring_report* report )
{
	if ( topology == NULL || p == NULL || params == NULL || fx == NULL || fy == NULL || fz == NULL ||
		 p->count != topology->vertex_count || !( params->dt > 0.0f ) || params->max_sweeps < 1 )
	{
		return SERE_ERR_ARGUMENT;
	}
	ref_forces( topology, p, params, fx, fy, fz );
	ref_euler( p, params, fx, fy, fz );

	/* Tang Eq. 2: sweeps repeat until one finds nothing more than δ off the narrowed band and
	 * every spring is inside the true band. Springs limited count from the first sweep. */
	int32_t sweeps = 0, limited = 0;
	int converged = 0;
	while ( sweeps < params->max_sweeps && !converged )
	{
		int32_t found = 0;
		float worst = ref_limit_sweep( topology, p, params, &found );
		limited += sweeps == 0 ? found : 0;
		++sweeps;
		converged = worst <= params->strain_tolerance && ref_within_band( topology, p, params );
	}

	const float dt = params->dt;
	for ( int32_t i = 0; i < p->count; ++i )
	{
		p->x[i] += p->vx[i] * dt;
		p->y[i] += p->vy[i] * dt;
		p->z[i] += p->vz[i] * dt;
	}
	float strain = 0.0f;
	for ( int32_t s = 0; s < topology->structural_count; ++s )
	{
		const int32_t a = topology->a[s], b = topology->b[s];
		float dx = p->x[b] - p->x[a], dy = p->y[b] - p->y[a], dz = p->z[b] - p->z[a];
		float rest = topology->rest0[s] * ( 1.0f - params->shrink );
		strain = fmaxf( strain, fabsf( sqrtf( dx * dx + dy * dy + dz * dz ) / rest - 1.0f ) );
	}
	if ( report != NULL )
	{
		report->sweeps = sweeps;
		report->limited = limited;
		report->max_strain = strain;
		report->hit_cap = !converged;
	}
	return converged ? SERE_OK : SERE_ERR_NO_CONVERGE;
}
