#include "ref/collide_ref.h"

#include "solve/collide.h"

#include <math.h>
#include <stdlib.h>

/* Whether vertex i shares an edge with a corner of the triangle v: some triangle holds both. */
static int near_corner( const int32_t* tri, int32_t triangle_count, int32_t i, const int32_t* v )
{
	for ( int32_t t = 0; t < triangle_count; ++t )
	{
		const int32_t* u = tri + 3 * (size_t) t;
		int has_i = u[0] == i || u[1] == i || u[2] == i;
		for ( int r = 0; r < 3 && has_i; ++r )
		{
			if ( u[0] == v[r] || u[1] == v[r] || u[2] == v[r] )
			{
				return 1;
			}
		}
	}
	return 0;
}

int64_t sere_collide_ref_pairs( const float* x, const float* y, const float* z, int32_t vertex_count,
								const int32_t* tri, int32_t triangle_count, float thickness, int32_t* vertex,
								int32_t* triangle, int64_t capacity )
{
	float h2 = thickness * thickness;
	int64_t count = 0;
	for ( int32_t i = 0; i < vertex_count; ++i )
	{
		float p[3] = { x[i], y[i], z[i] };
		for ( int32_t t = 0; t < triangle_count; ++t )
		{
			const int32_t* v = tri + 3 * (size_t) t;
			if ( v[0] == i || v[1] == i || v[2] == i )
			{
				continue;
			}
			float a[3] = { x[v[0]], y[v[0]], z[v[0]] };
			float b[3] = { x[v[1]], y[v[1]], z[v[1]] };
			float c[3] = { x[v[2]], y[v[2]], z[v[2]] };
			float w[3];
			if ( sere_closest_point_triangle( p, a, b, c, w ) < h2 &&
				 ( ( w[0] > 0.0f && w[1] > 0.0f && w[2] > 0.0f ) || !near_corner( tri, triangle_count, i, v ) ) )
			{
				if ( count < capacity )
				{
					vertex[count] = i;
					triangle[count] = t;
				}
				count += 1;
			}
		}
	}
	return count;
}

static double dot3( const double u[3], const double v[3] )
{
	return u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
}

static double segment_distance2( const double p[3], const double a[3], const double b[3] )
{
	double ab[3] = { b[0] - a[0], b[1] - a[1], b[2] - a[2] };
	double ap[3] = { p[0] - a[0], p[1] - a[1], p[2] - a[2] };
	double len2 = dot3( ab, ab );
	double t = len2 > 0.0 ? dot3( ap, ab ) / len2 : 0.0;
	t = t < 0.0 ? 0.0 : ( t > 1.0 ? 1.0 : t );
	double d[3] = { ap[0] - t * ab[0], ap[1] - t * ab[1], ap[2] - t * ab[2] };
	return dot3( d, d );
}

static int compare_edge( const void* a, const void* b )
{
	const int32_t *u = a, *v = b;
	return u[0] != v[0] ? ( u[0] > v[0] ) - ( u[0] < v[0] ) : ( u[1] > v[1] ) - ( u[1] < v[1] );
}

int64_t sere_collide_ref_edge_pairs( const float* x, const float* y, const float* z, const float* rx, const float* ry,
									 const float* rz, const int32_t* tri, int32_t triangle_count, float thickness,
									 int32_t* ends, float* weights, int64_t capacity )
{
	/* every triangle side, lower vertex first, sorted, repeats and zero-length sides dropped */
	int32_t* edge = malloc( sizeof( int32_t ) * 6 * ( (size_t) triangle_count + 1 ) );
	if ( edge == NULL )
	{
		return -1;
	}
	int64_t sides = 0;
	for ( int32_t t = 0; t < triangle_count; ++t )
	{
		for ( int r = 0; r < 3; ++r )
		{
			int32_t i = tri[3 * t + r], j = tri[3 * t + ( r + 1 ) % 3];
			if ( i != j )
			{
				edge[2 * sides] = i < j ? i : j, edge[2 * sides + 1] = i < j ? j : i;
				sides += 1;
			}
		}
	}
	qsort( edge, (size_t) sides, 2 * sizeof( int32_t ), compare_edge );
	int64_t edges = 0;
	for ( int64_t k = 0; k < sides; ++k )
	{
		if ( edges == 0 || compare_edge( edge + 2 * k, edge + 2 * ( edges - 1 ) ) != 0 )
		{
			edge[2 * edges] = edge[2 * k], edge[2 * edges + 1] = edge[2 * k + 1];
			edges += 1;
		}
	}
	float h2 = thickness * thickness;
	int64_t count = 0;
	for ( int64_t e = 0; e < edges; ++e )
	{
		int32_t a0 = edge[2 * e], a1 = edge[2 * e + 1];
		float p0[3] = { x[a0], y[a0], z[a0] }, p1[3] = { x[a1], y[a1], z[a1] };
		for ( int64_t f = e + 1; f < edges; ++f )
		{
			int32_t b0 = edge[2 * f], b1 = edge[2 * f + 1];
			if ( a0 == b0 || a0 == b1 || a1 == b0 || a1 == b1 )
			{
				continue;
			}
			float q0[3] = { x[b0], y[b0], z[b0] }, q1[3] = { x[b1], y[b1], z[b1] };
			float w[2];
			float d2 = sere_closest_points_segments( p0, p1, q0, q1, w );
			if ( !( d2 < h2 && w[0] > 0.0f && w[0] < 1.0f && w[1] > 0.0f && w[1] < 1.0f ) )
			{
				continue;
			}
			if ( rx != NULL )
			{
				float r0[3] = { rx[a0], ry[a0], rz[a0] }, r1[3] = { rx[a1], ry[a1], rz[a1] };
				float s0[3] = { rx[b0], ry[b0], rz[b0] }, s1[3] = { rx[b1], ry[b1], rz[b1] }, rest[2];
				if ( sere_closest_points_segments( r0, r1, s0, s1, rest ) < h2 )
				{
					continue;
				}
			}
			if ( count < capacity )
			{
				ends[4 * count] = a0, ends[4 * count + 1] = a1, ends[4 * count + 2] = b0, ends[4 * count + 3] = b1;
				if ( weights != NULL )
				{
					weights[2 * count] = w[0], weights[2 * count + 1] = w[1];
				}
			}
			count += 1;
		}
	}
	free( edge );
	return count;
}

double sere_collide_ref_segment_distance2( const double p0[3], const double p1[3], const double q0[3],
										   const double q1[3] )
{
	double u[3] = { p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2] };
	double v[3] = { q1[0] - q0[0], q1[1] - q0[1], q1[2] - q0[2] };
	double w[3] = { p0[0] - q0[0], p0[1] - q0[1], p0[2] - q0[2] };
	double a = dot3( u, u ), b = dot3( u, v ), c = dot3( v, v ), d = dot3( u, w ), e = dot3( v, w );
	double denom = a * c - b * b;
	if ( denom > 1e-12 * a * c )
	{
		/* Cramer's rule for the lines' closest points */
		double s = ( b * e - c * d ) / denom, t = ( a * e - b * d ) / denom;
		if ( s >= 0.0 && s <= 1.0 && t >= 0.0 && t <= 1.0 )
		{
			double g[3] = { w[0] + s * u[0] - t * v[0], w[1] + s * u[1] - t * v[1], w[2] + s * u[2] - t * v[2] };
			return dot3( g, g );
		}
	}
	double best = segment_distance2( p0, q0, q1 );
	double other[3] = { segment_distance2( p1, q0, q1 ), segment_distance2( q0, p0, p1 ),
						segment_distance2( q1, p0, p1 ) };
	for ( int k = 0; k < 3; ++k )
	{
		best = other[k] < best ? other[k] : best;
	}
	return best;
}

double sere_collide_ref_distance2( const double p[3], const double a[3], const double b[3], const double c[3] )
{
	double ab[3] = { b[0] - a[0], b[1] - a[1], b[2] - a[2] };
	double ac[3] = { c[0] - a[0], c[1] - a[1], c[2] - a[2] };
	double ap[3] = { p[0] - a[0], p[1] - a[1], p[2] - a[2] };
	double n[3] = { ab[1] * ac[2] - ab[2] * ac[1], ab[2] * ac[0] - ab[0] * ac[2], ab[0] * ac[1] - ab[1] * ac[0] };
	double n2 = dot3( n, n );
	if ( n2 > 0.0 )
	{
		/* barycentric coordinates of the projection from the sub-triangle areas */
		double s = dot3( ap, n ) / n2;
		double q[3] = { ap[0] - s * n[0], ap[1] - s * n[1], ap[2] - s * n[2] };
		double qb[3] = { q[0] - ab[0], q[1] - ab[1], q[2] - ab[2] };
		double qc[3] = { q[0] - ac[0], q[1] - ac[1], q[2] - ac[2] };
		double cross_bc[3] = { qb[1] * qc[2] - qb[2] * qc[1], qb[2] * qc[0] - qb[0] * qc[2],
							   qb[0] * qc[1] - qb[1] * qc[0] };
		double cross_ca[3] = { qc[1] * q[2] - qc[2] * q[1], qc[2] * q[0] - qc[0] * q[2], qc[0] * q[1] - qc[1] * q[0] };
		double cross_ab[3] = { q[1] * qb[2] - q[2] * qb[1], q[2] * qb[0] - q[0] * qb[2], q[0] * qb[1] - q[1] * qb[0] };
		if ( dot3( cross_bc, n ) >= 0.0 && dot3( cross_ca, n ) >= 0.0 && dot3( cross_ab, n ) >= 0.0 )
		{
			return s * s * n2;
		}
	}
	double dab = segment_distance2( p, a, b );
	double dbc = segment_distance2( p, b, c );
	double dca = segment_distance2( p, c, a );
	double d = dab < dbc ? dab : dbc;
	return d < dca ? d : dca;
}

static void ref_normal( const float* x, const float* y, const float* z, const int32_t* v, double n[3] )
{
	double ab[3] = { (double) x[v[1]] - x[v[0]], (double) y[v[1]] - y[v[0]], (double) z[v[1]] - z[v[0]] };
	double ac[3] = { (double) x[v[2]] - x[v[0]], (double) y[v[2]] - y[v[0]], (double) z[v[2]] - z[v[0]] };
	n[0] = ab[1] * ac[2] - ab[2] * ac[1];
	n[1] = ab[2] * ac[0] - ab[0] * ac[2];
	n[2] = ab[0] * ac[1] - ab[1] * ac[0];
	double length = sqrt( dot3( n, n ) );
	for ( int k = 0; k < 3; ++k )
	{
		n[k] = length > 0.0 ? n[k] / length : 0.0;
	}
}

void sere_collide_ref_measure_h( const float* x, const float* y, const float* z, const int32_t* tri,
								 int32_t triangle_count, int32_t voronoi_first, double* h_hat )
{
	for ( int32_t t = 0; t < triangle_count; ++t )
	{
		const int32_t* v = tri + 3 * (size_t) t;
		int32_t i = voronoi_first + t;
		double n[3];
		ref_normal( x, y, z, v, n );
		h_hat[t] = ( (double) x[i] - x[v[0]] ) * n[0] + ( (double) y[i] - y[v[0]] ) * n[1] +
				   ( (double) z[i] - z[v[0]] ) * n[2];
	}
}

void sere_collide_ref_restore_voronoi( double* x, double* y, double* z, double* vx, double* vy, double* vz,
									   const int32_t* tri, int32_t triangle_count, int32_t voronoi_first,
									   const double* h )
{
	for ( int32_t t = 0; t < triangle_count; ++t )
	{
		const int32_t* v = tri + 3 * (size_t) t;
		int32_t i = voronoi_first + t;
		double ab[3] = { x[v[1]] - x[v[0]], y[v[1]] - y[v[0]], z[v[1]] - z[v[0]] };
		double ac[3] = { x[v[2]] - x[v[0]], y[v[2]] - y[v[0]], z[v[2]] - z[v[0]] };
		double n[3] = { ab[1] * ac[2] - ab[2] * ac[1], ab[2] * ac[0] - ab[0] * ac[2], ab[0] * ac[1] - ab[1] * ac[0] };
		double length = sqrt( dot3( n, n ) );
		for ( int k = 0; k < 3; ++k )
		{
			n[k] = length > 0.0 ? n[k] / length : 0.0;
		}
		x[i] = ( x[v[0]] + x[v[1]] + x[v[2]] ) / 3.0 + h[t] * n[0];
		y[i] = ( y[v[0]] + y[v[1]] + y[v[2]] ) / 3.0 + h[t] * n[1];
		z[i] = ( z[v[0]] + z[v[1]] + z[v[2]] ) / 3.0 + h[t] * n[2];
		vx[i] = ( vx[v[0]] + vx[v[1]] + vx[v[2]] ) / 3.0;
		vy[i] = ( vy[v[0]] + vy[v[1]] + vy[v[2]] ) / 3.0;
		vz[i] = ( vz[v[0]] + vz[v[1]] + vz[v[2]] ) / 3.0;
	}
}
