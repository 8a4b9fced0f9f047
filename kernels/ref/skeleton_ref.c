#include "ref/skeleton_ref.h"

#include <math.h>

void sere_skeleton_ref_band( const float* jx, const float* jy, const float* jz, int32_t joint_count, const float* x,
							 const float* y, const float* z, int32_t vertex_count, int32_t* joint )
{
	for ( int32_t i = 0; i < vertex_count; ++i )
	{
		int32_t best = -1;
		float best_d2 = INFINITY;
		for ( int32_t j = 0; j < joint_count; ++j )
		{
			float dx = x[i] - jx[j], dy = y[i] - jy[j], dz = z[i] - jz[j];
			float d2 = dx * dx + dy * dy + dz * dz;
			if ( d2 < best_d2 )
			{
				best_d2 = d2;
				best = j;
			}
		}
		joint[i] = best;
	}
}

void sere_skeleton_ref_skin( const sere_joint_frames* frames, const int32_t* joint, const float* ox, const float* oy,
							 const float* oz, int32_t vertex_count, float* x, float* y, float* z )
{
	for ( int32_t i = 0; i < vertex_count; ++i )
	{
		int32_t j = joint[i];
		float* const* m = frames->m;
		x[i] = frames->x[j] + ( ( m[0][j] * ox[i] + m[1][j] * oy[i] ) + m[2][j] * oz[i] );
		y[i] = frames->y[j] + ( ( m[3][j] * ox[i] + m[4][j] * oy[i] ) + m[5][j] * oz[i] );
		z[i] = frames->z[j] + ( ( m[6][j] * ox[i] + m[7][j] * oy[i] ) + m[8][j] * oz[i] );
	}
}

static int descends_from( const sere_skeleton* s, int32_t k, int32_t i )
{
	while ( k >= 0 )
	{
		if ( k == i )
		{
			return 1;
		}
		k = s->parent[k];
	}
	return 0;
}

void sere_skeleton_ref_pose( const sere_skeleton* s, float t, float spread, double* x, double* y, double* z )
{
	int32_t n = s->joint_count;
	for ( int32_t k = 0; k < n; ++k )
	{
		x[k] = s->x[k];
		y[k] = s->y[k];
		z[k] = s->z[k];
	}
	for ( int32_t i = 0; i < n; ++i )
	{
		int32_t p = s->parent[i];
		if ( p < 0 )
		{
			continue;
		}
		double u[3] = { x[i] - x[p], y[i] - y[p], z[i] - z[p] };
		double length = sqrt( u[0] * u[0] + u[1] * u[1] + u[2] * u[2] );
		double horizontal = sqrt( u[0] * u[0] + u[1] * u[1] );
		double progress = ( t - spread * s->delay[i] ) / ( 1.0 - spread );
		progress = progress < 0.0 ? 0.0 : ( progress > 1.0 ? 1.0 : progress );
		double phi = s->bend[i] * progress;
		if ( phi <= 0.0 || horizontal <= 1e-12 * length )
		{
			continue;
		}
		/* The angle between u and d = (0, 0, −1). */
		double omega = acos( fmax( -1.0, fmin( 1.0, -u[2] / length ) ) );
		phi = phi < omega ? phi : omega;
		double n_axis[3] = { -u[1] / horizontal, u[0] / horizontal, 0.0 };
		double c = cos( phi ), sn = sin( phi );
		for ( int32_t k = i; k < n; ++k )
		{
			if ( !descends_from( s, k, i ) )
			{
				continue;
			}
			/* Rodrigues about the axis through the parent joint; for k = i this is Lu Eq. 1,
			 * P(φ) = P_p + |u| (cos φ û + sin φ (n × û)), since n ⟂ u. */
			double v[3] = { x[k] - x[p], y[k] - y[p], z[k] - z[p] };
			double nv = n_axis[0] * v[0] + n_axis[1] * v[1];
			double cross[3] = { n_axis[1] * v[2], -n_axis[0] * v[2], n_axis[0] * v[1] - n_axis[1] * v[0] };
			double r[3];
			for ( int a = 0; a < 3; ++a )
			{
				r[a] = v[a] * c + cross[a] * sn + n_axis[a] * nv * ( 1.0 - c );
			}
			x[k] = x[p] + r[0];
			y[k] = y[p] + r[1];
			z[k] = z[p] + r[2];
		}
	}
}
