#include "ref/measure_ref.h"

#include "mesh/measure.h"

#include <math.h>

/* Whether triangles 0 .. t − 1, or the corners of t before k, already hold edge (i, j). */
static int edge_seen( const int32_t* tri, int32_t t, int k, int32_t i, int32_t j )
{
	for ( int32_t s = 0; s <= t; ++s )
	{
		int corners = s < t ? 3 : k;
		for ( int r = 0; r < corners; ++r )
		{
			int32_t a = tri[3 * (size_t) s + r], b = tri[3 * (size_t) s + ( r + 1 ) % 3];
			if ( ( a == i && b == j ) || ( a == j && b == i ) )
			{
				return 1;
			}
		}
	}
	return 0;
}

int64_t sere_crossings_ref_count( const float* x, const float* y, const float* z, int32_t vertex_count,
								  const int32_t* tri, int32_t tri_count )
{
	(void) vertex_count;
	int64_t count = 0;
	for ( int32_t t = 0; t < tri_count; ++t )
	{
		for ( int k = 0; k < 3; ++k )
		{
			int32_t i = tri[3 * (size_t) t + k], j = tri[3 * (size_t) t + ( k + 1 ) % 3];
			if ( i == j || edge_seen( tri, t, k, i, j ) )
			{
				continue;
			}
			double p[3] = { x[i], y[i], z[i] }, q[3] = { x[j], y[j], z[j] };
			for ( int32_t s = 0; s < tri_count; ++s )
			{
				count += sere_edge_crosses_triangle( p, q, i, j, tri + 3 * (size_t) s, x, y, z );
			}
		}
	}
	return count;
}

static void ref_cross( const double u[3], const double v[3], double out[3] )
{
	out[0] = u[1] * v[2] - u[2] * v[1];
	out[1] = u[2] * v[0] - u[0] * v[2];
	out[2] = u[0] * v[1] - u[1] * v[0];
}

static double ref_dot( const double u[3], const double v[3] )
{
	return u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
}

static void ref_normal( const float* x, const float* y, const float* z, const int32_t* v, double n[3] )
{
	double ab[3] = { (double) x[v[1]] - x[v[0]], (double) y[v[1]] - y[v[0]], (double) z[v[1]] - z[v[0]] };
	double ac[3] = { (double) x[v[2]] - x[v[0]], (double) y[v[2]] - y[v[0]], (double) z[v[2]] - z[v[0]] };
	ref_cross( ab, ac, n );
}

void sere_shape_ref_dihedrals( const float* x, const float* y, const float* z, const int32_t* tri, int32_t tri_count,
							   const int32_t* edge_a, const int32_t* edge_b, int32_t edge_count, double* dihedral,
							   double* area )
{
	*area = 0.0;
	for ( int32_t t = 0; t < tri_count; ++t )
	{
		double n[3];
		ref_normal( x, y, z, tri + 3 * (size_t) t, n );
		*area += 0.5 * sqrt( ref_dot( n, n ) );
	}
	for ( int32_t e = 0; e < edge_count; ++e )
	{
		int32_t a = edge_a[e], b = edge_b[e];
		int32_t forward = -1, backward = -1, holders = 0, off = -1;
		for ( int32_t t = 0; t < tri_count; ++t )
		{
			for ( int k = 0; k < 3; ++k )
			{
				int32_t i = tri[3 * (size_t) t + k], j = tri[3 * (size_t) t + ( k + 1 ) % 3];
				if ( i == a && j == b )
				{
					forward = t, holders += 1;
				}
				else if ( i == b && j == a )
				{
					backward = t, holders += 1;
					off = tri[3 * (size_t) t + ( k + 2 ) % 3];
				}
			}
		}
		dihedral[e] = 0.0;
		if ( holders != 2 || forward < 0 || backward < 0 )
		{
			continue;
		}
		double n0[3], n1[3], w[3];
		ref_normal( x, y, z, tri + 3 * (size_t) forward, n0 );
		ref_normal( x, y, z, tri + 3 * (size_t) backward, n1 );
		double l0 = sqrt( ref_dot( n0, n0 ) ), l1 = sqrt( ref_dot( n1, n1 ) );
		if ( !( l0 > 0.0 ) || !( l1 > 0.0 ) )
		{
			continue;
		}
		for ( int k = 0; k < 3; ++k )
		{
			n0[k] /= l0, n1[k] /= l1;
		}
		ref_cross( n0, n1, w );
		double magnitude = atan2( sqrt( ref_dot( w, w ) ), ref_dot( n0, n1 ) );
		double lift[3] = { (double) x[off] - x[a], (double) y[off] - y[a], (double) z[off] - z[a] };
		dihedral[e] = ref_dot( n0, lift ) < 0.0 ? -magnitude : magnitude;
	}
}
