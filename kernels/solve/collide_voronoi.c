/* sere — the Voronoi particles of the triangle layer: their heights over their triangles, measured and restored after
 * the collision pass. _GNU_SOURCE: sched_getaffinity for internal/team.h. */
#define _GNU_SOURCE

#include "solve/internal/collide_shared.h"

/* Algorithm 1 line 14: the height of particle i (in x, y, z) over triangle v (corners in cx, cy,
 * cz) along its unit normal, from corner a. */
static inline float voronoi_height( const float* cx, const float* cy, const float* cz, const float* x, const float* y,
									const float* z, const int32_t* v, int32_t i )
{
	float a[3], b[3], c[3], n[3], p[3];
	triangle_frame( cx, cy, cz, v, a, b, c, n );
	load3( x, y, z, i, p );
	return ( p[0] - a[0] ) * n[0] + ( p[1] - a[1] ) * n[1] + ( p[2] - a[2] ) * n[2];
}

sere_status sere_collide_measure_h( const float* x, const float* y, const float* z, const int32_t* tri,
									int32_t triangle_count, int32_t voronoi_first, float* h_hat, int32_t threads )
{
	if ( x == NULL || y == NULL || z == NULL || tri == NULL || h_hat == NULL || triangle_count < 0 ||
		 voronoi_first < 0 || !sere_threads_valid( threads ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	int bad = 0;
#pragma omp parallel for num_threads( sere_team_for( threads ) ) reduction( | : bad ) schedule( static )
	for ( int32_t t = 0; t < triangle_count; ++t )
	{
		float h = voronoi_height( x, y, z, x, y, z, tri + 3 * (size_t) t, voronoi_first + t );
		/* a NaN or infinity in any of the four points reaches h through n or the difference */
		bad |= !isfinite( h );
		h_hat[t] = isfinite( h ) ? h : 0.0f;
	}
	return bad ? SERE_ERR_NONFINITE : SERE_OK;
}

sere_status sere_collide_measure_h_moved( const float* cx, const float* cy, const float* cz, const float* x,
										  const float* y, const float* z, const int32_t* tri, int32_t triangle_count,
										  int32_t voronoi_first, const uint8_t* moved, float* h_hat, int32_t threads )
{
	if ( cx == NULL || cy == NULL || cz == NULL || x == NULL || y == NULL || z == NULL || tri == NULL ||
		 moved == NULL || h_hat == NULL || triangle_count < 0 || voronoi_first < 0 || !sere_threads_valid( threads ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	int bad = 0, outside = 0;
#pragma omp parallel for num_threads( sere_team_for( threads ) ) reduction( | : bad, outside ) schedule( static )
	for ( int32_t t = 0; t < triangle_count; ++t )
	{
		const int32_t* v = tri + 3 * (size_t) t;
		/* the corners index cx and moved, both voronoi_first long */
		if ( v[0] < 0 || v[0] >= voronoi_first || v[1] < 0 || v[1] >= voronoi_first || v[2] < 0 ||
			 v[2] >= voronoi_first )
		{
			outside = 1;
			continue;
		}
		if ( !( moved[v[0]] | moved[v[1]] | moved[v[2]] ) )
		{
			continue;
		}
		float h = voronoi_height( cx, cy, cz, x, y, z, v, voronoi_first + t );
		bad |= !isfinite( h );
		h_hat[t] = isfinite( h ) ? h : 0.0f;
	}
	if ( outside )
	{
		return SERE_ERR_ARGUMENT;
	}
	return bad ? SERE_ERR_NONFINITE : SERE_OK;
}

/* Jeong Eq. 14: the Voronoi particle of triangle (a, b, c) with unit normal n at height h above
 * the triangle's centroid. */
static inline void voronoi_target( const float a[3], const float b[3], const float c[3], const float n[3], float h,
								   float out[3] )
{
	for ( int k = 0; k < 3; ++k )
	{
		out[k] = ( a[k] + b[k] + c[k] ) / 3.0f + h * n[k];
	}
}

sere_status sere_collide_restore_voronoi( float* x, float* y, float* z, float* vx, float* vy, float* vz,
										  const int32_t* tri, int32_t triangle_count, int32_t voronoi_first,
										  const float* h, int32_t threads )
{
	if ( x == NULL || y == NULL || z == NULL || vx == NULL || vy == NULL || vz == NULL || tri == NULL || h == NULL ||
		 triangle_count < 0 || voronoi_first < 0 || !sere_threads_valid( threads ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	/* Check everything read before writing anything: the corners (all below voronoi_first, so
	 * contiguous scans, and never a Voronoi particle being written) and the thicknesses. */
	/* Two reductions in one region need two variables: with a shared one, the first loop's
	 * combine could race with the second's. */
	int bad = 0, bad_h = 0, outside = 0;
#pragma omp parallel num_threads( sere_team_for( threads ) )
	{
#pragma omp for reduction( | : bad ) schedule( static ) nowait
		for ( int32_t i = 0; i < voronoi_first; ++i )
		{
			bad |= !( isfinite( x[i] ) && isfinite( y[i] ) && isfinite( z[i] ) && isfinite( vx[i] ) &&
					  isfinite( vy[i] ) && isfinite( vz[i] ) );
		}
#pragma omp for reduction( | : bad_h, outside ) schedule( static )
		for ( int32_t t = 0; t < triangle_count; ++t )
		{
			bad_h |= !isfinite( h[t] );
			outside |= tri[3 * t] < 0 || tri[3 * t] >= voronoi_first || tri[3 * t + 1] < 0 ||
					   tri[3 * t + 1] >= voronoi_first || tri[3 * t + 2] < 0 || tri[3 * t + 2] >= voronoi_first;
		}
	}
	if ( outside )
	{
		return SERE_ERR_ARGUMENT;
	}
	if ( bad || bad_h )
	{
		return SERE_ERR_NONFINITE;
	}
#pragma omp parallel for num_threads( sere_team_for( threads ) ) schedule( static )
	for ( int32_t t = 0; t < triangle_count; ++t )
	{
		const int32_t* v = tri + 3 * (size_t) t;
		float a[3], b[3], c[3], n[3];
		triangle_frame( x, y, z, v, a, b, c, n );
		int32_t i = voronoi_first + t;
		float target[3];
		voronoi_target( a, b, c, n, h[t], target );
		x[i] = target[0], y[i] = target[1], z[i] = target[2];
		vx[i] = ( vx[v[0]] + vx[v[1]] + vx[v[2]] ) / 3.0f;
		vy[i] = ( vy[v[0]] + vy[v[1]] + vy[v[2]] ) / 3.0f;
		vz[i] = ( vz[v[0]] + vz[v[1]] + vz[v[2]] ) / 3.0f;
	}
	return SERE_OK;
}

sere_status sere_collide_restore_voronoi_moved( float* x, float* y, float* z, float* vx, float* vy, float* vz,
												const int32_t* tri, int32_t triangle_count, int32_t voronoi_first,
												const float* h, const uint8_t* moved, float dt, int32_t threads )
{
	if ( x == NULL || y == NULL || z == NULL || vx == NULL || vy == NULL || vz == NULL || tri == NULL || h == NULL ||
		 moved == NULL || triangle_count < 0 || voronoi_first < 0 || !( dt > 0.0f ) || !sere_threads_valid( threads ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	int bad = 0, outside = 0;
#pragma omp parallel for num_threads( sere_team_for( threads ) ) reduction( | : bad, outside ) schedule( static )
	for ( int32_t t = 0; t < triangle_count; ++t )
	{
		const int32_t* v = tri + 3 * (size_t) t;
		outside |=
			v[0] < 0 || v[0] >= voronoi_first || v[1] < 0 || v[1] >= voronoi_first || v[2] < 0 || v[2] >= voronoi_first;
		bad |= !isfinite( h[t] );
	}
	if ( outside )
	{
		return SERE_ERR_ARGUMENT;
	}
	if ( bad )
	{
		return SERE_ERR_NONFINITE;
	}
	const float inv_dt = 1.0f / dt;
#pragma omp parallel for num_threads( sere_team_for( threads ) ) schedule( static )
	for ( int32_t t = 0; t < triangle_count; ++t )
	{
		const int32_t* v = tri + 3 * (size_t) t;
		if ( !( moved[v[0]] | moved[v[1]] | moved[v[2]] ) )
		{
			continue;
		}
		float a[3], b[3], c[3], n[3];
		triangle_frame( x, y, z, v, a, b, c, n );
		int32_t i = voronoi_first + t;
		/* only a Voronoi particle the collision pushed through its triangle (Sec. 5.3) */
		float height = ( x[i] - ( a[0] + b[0] + c[0] ) / 3.0f ) * n[0] +
					   ( y[i] - ( a[1] + b[1] + c[1] ) / 3.0f ) * n[1] +
					   ( z[i] - ( a[2] + b[2] + c[2] ) / 3.0f ) * n[2];
		if ( height * h[t] > 0.0f )
		{
			continue;
		}
		float target[3];
		voronoi_target( a, b, c, n, h[t], target );
		const float tx = target[0], ty = target[1], tz = target[2];
		/* Sec. 5.2: a position change Δx changes the velocity by Δx/Δt, as every other
		 * correction of the frame does. */
		vx[i] += ( tx - x[i] ) * inv_dt;
		vy[i] += ( ty - y[i] ) * inv_dt;
		vz[i] += ( tz - z[i] ) * inv_dt;
		x[i] = tx, y[i] = ty, z[i] = tz;
	}
	return SERE_OK;
}
