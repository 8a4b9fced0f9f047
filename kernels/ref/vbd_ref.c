#include "ref/vbd_ref.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct adjacency
{
	int32_t *offset, *spring;
} adjacency;

static int adjacency_make( const sere_vbd_ref_problem* p, adjacency* adj )
{
	adj->offset = calloc( (size_t) p->particle_count + 1, sizeof( int32_t ) );
	adj->spring = malloc( sizeof( int32_t ) * ( 2 * (size_t) p->spring_count + 1 ) );
	int32_t* fill = malloc( sizeof( int32_t ) * ( (size_t) p->particle_count + 1 ) );
	if ( adj->offset == NULL || adj->spring == NULL || fill == NULL )
	{
		free( adj->offset ), free( adj->spring ), free( fill );
		return 0;
	}
	for ( int32_t k = 0; k < p->spring_count; ++k )
	{
		adj->offset[p->a[k] + 1] += 1, adj->offset[p->b[k] + 1] += 1;
	}
	for ( int32_t i = 0; i < p->particle_count; ++i )
	{
		adj->offset[i + 1] += adj->offset[i];
	}
	memcpy( fill, adj->offset, sizeof( int32_t ) * (size_t) p->particle_count );
	for ( int32_t k = 0; k < p->spring_count; ++k )
	{
		adj->spring[fill[p->a[k]]++] = k, adj->spring[fill[p->b[k]]++] = k;
	}
	free( fill );
	return 1;
}

/* ∂E/∂x_i into g and, when H is not NULL, particle i's 3 × 3 block into H. */
static void block( const sere_vbd_ref_problem* p, const adjacency* adj, const double* x, int32_t i, double g[3],
				   double H[9] )
{
	const double m = 1.0 / p->inv_m[i], t[3] = { p->tx[i], p->ty[i], p->tz[i] };
	for ( int r = 0; r < 3; ++r )
	{
		g[r] = m * ( x[3 * i + r] - t[r] );
		for ( int c = 0; H != NULL && c < 3; ++c )
		{
			H[3 * r + c] = r == c ? m : 0.0;
		}
	}
	for ( int32_t e = adj->offset[i]; e < adj->offset[i + 1]; ++e )
	{
		const int32_t j = adj->spring[e], o = p->a[j] == i ? p->b[j] : p->a[j];
		const double d[3] = { x[3 * i] - x[3 * o], x[3 * i + 1] - x[3 * o + 1], x[3 * i + 2] - x[3 * o + 2] };
		const double length = sqrt( d[0] * d[0] + d[1] * d[1] + d[2] * d[2] );
		if ( length == 0.0 )
		{
			continue; /* no direction: the spring pushes nowhere */
		}
		const double c = length - p->rest[j], bend = c > 0.0 ? c / length : 0.0, k = p->stiffness[j];
		for ( int r = 0; r < 3; ++r )
		{
			g[r] += k * c * d[r] / length;
			for ( int q = 0; H != NULL && q < 3; ++q )
			{
				const double nn = d[r] * d[q] / ( length * length );
				H[3 * r + q] += k * ( nn + bend * ( ( r == q ) - nn ) );
			}
		}
	}
}

static double largest_gradient( const sere_vbd_ref_problem* p, const adjacency* adj, const double* x )
{
	double worst = 0.0;
	for ( int32_t i = 0; i < p->particle_count; ++i )
	{
		if ( p->inv_m[i] > 0.0f )
		{
			double g[3];
			block( p, adj, x, i, g, NULL );
			worst = fmax( worst, sqrt( g[0] * g[0] + g[1] * g[1] + g[2] * g[2] ) );
		}
	}
	return worst;
}

double sere_vbd_ref_gradient( const sere_vbd_ref_problem* problem, const double* x )
{
	adjacency adj;
	if ( !adjacency_make( problem, &adj ) )
	{
		return -1.0;
	}
	const double worst = largest_gradient( problem, &adj, x );
	free( adj.offset ), free( adj.spring );
	return worst;
}

int32_t sere_vbd_ref_descend( const sere_vbd_ref_problem* problem, double* x, double tolerance, int32_t max_sweeps )
{
	adjacency adj;
	if ( !adjacency_make( problem, &adj ) )
	{
		return -1;
	}
	int32_t sweeps = 0;
	while ( largest_gradient( problem, &adj, x ) >= tolerance )
	{
		if ( sweeps == max_sweeps )
		{
			sweeps = -1;
			break;
		}
		for ( int32_t i = 0; i < problem->particle_count; ++i )
		{
			if ( !( problem->inv_m[i] > 0.0f ) )
			{
				continue;
			}
			double g[3], H[9];
			block( problem, &adj, x, i, g, H );
			/* Δ = −H⁻¹ g by the adjugate */
			const double c0 = H[4] * H[8] - H[5] * H[7], c1 = H[5] * H[6] - H[3] * H[8];
			const double c2 = H[3] * H[7] - H[4] * H[6], det = H[0] * c0 + H[1] * c1 + H[2] * c2;
			const double inv[9] = { c0, H[2] * H[7] - H[1] * H[8], H[1] * H[5] - H[2] * H[4],
									c1, H[0] * H[8] - H[2] * H[6], H[2] * H[3] - H[0] * H[5],
									c2, H[1] * H[6] - H[0] * H[7], H[0] * H[4] - H[1] * H[3] };
			for ( int r = 0; r < 3; ++r )
			{
				x[3 * i + r] -= ( inv[3 * r] * g[0] + inv[3 * r + 1] * g[1] + inv[3 * r + 2] * g[2] ) / det;
			}
		}
		sweeps += 1;
	}
	free( adj.offset ), free( adj.spring );
	return sweeps;
}
