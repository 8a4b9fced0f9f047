#include "ref/osmosis_ref.h"

#include <math.h>
#include <stdlib.h>

sere_status sere_dense_ref_solve( double* A, double* rhs, double* x, int32_t n )
{
	for ( int32_t col = 0; col < n; ++col )
	{
		int32_t pivot = col;
		for ( int32_t r = col + 1; r < n; ++r )
		{
			if ( fabs( A[(size_t) r * n + col] ) > fabs( A[(size_t) pivot * n + col] ) )
			{
				pivot = r;
			}
		}
		if ( A[(size_t) pivot * n + col] == 0.0 )
		{
			return SERE_ERR_GEOMETRY;
		}
		if ( pivot != col )
		{
			for ( int32_t k = 0; k < n; ++k )
			{
				double t = A[(size_t) col * n + k];
				A[(size_t) col * n + k] = A[(size_t) pivot * n + k];
				A[(size_t) pivot * n + k] = t;
			}
			double t = rhs[col];
			rhs[col] = rhs[pivot];
			rhs[pivot] = t;
		}
		for ( int32_t r = col + 1; r < n; ++r )
		{
			double f = A[(size_t) r * n + col] / A[(size_t) col * n + col];
			if ( f != 0.0 )
			{
				for ( int32_t k = col; k < n; ++k )
				{
					A[(size_t) r * n + k] -= f * A[(size_t) col * n + k];
				}
				rhs[r] -= f * rhs[col];
			}
		}
	}
	for ( int32_t r = n - 1; r >= 0; --r )
	{
		double sum = rhs[r];
		for ( int32_t k = r + 1; k < n; ++k )
		{
			sum -= A[(size_t) r * n + k] * x[k];
		}
		x[r] = sum / A[(size_t) r * n + r];
	}
	return SERE_OK;
}

sere_status sere_osmosis_ref_step( int32_t first, int32_t count, const int32_t* a, const int32_t* b,
								   int32_t spring_count, const float* x, const float* y, const float* z,
								   const float* tau, const double* M, const double* w, double dt, double lambda_min,
								   double lambda_max, double water_rate, double* w_out )
{
	int32_t n = count;
	double* A = calloc( (size_t) n * (size_t) n, sizeof( double ) );
	double* rhs = malloc( sizeof( double ) * (size_t) n );
	double* E = calloc( (size_t) n, sizeof( double ) );
	if ( A == NULL || rhs == NULL || E == NULL )
	{
		free( A ), free( rhs ), free( E );
		return SERE_ERR_MEMORY;
	}
	for ( int32_t s = 0; s < spring_count; ++s )
	{
		double dx = (double) x[b[s]] - x[a[s]], dy = (double) y[b[s]] - y[a[s]], dz = (double) z[b[s]] - z[a[s]];
		double l = sqrt( dx * dx + dy * dy + dz * dz );
		E[a[s] - first] += l; /* Jeong Eq. 3: E = Σ |l_ij| */
		E[b[s] - first] += l;
	}
	for ( int32_t i = 0; i < n; ++i )
	{
		A[(size_t) i * n + i] = 1.0;
		rhs[i] = w[first + i] + water_rate * dt; /* Jeong Eq. 9 right-hand side, w_loss signed */
	}
	for ( int32_t s = 0; s < spring_count; ++s )
	{
		double dx = (double) x[b[s]] - x[a[s]], dy = (double) y[b[s]] - y[a[s]], dz = (double) z[b[s]] - z[a[s]];
		double l = sqrt( dx * dx + dy * dy + dz * dz );
		for ( int side = 0; side < 2; ++side )
		{
			int32_t gi = side == 0 ? a[s] : b[s], gj = side == 0 ? b[s] : a[s];
			int32_t i = gi - first, j = gj - first;
			double t = 0.5 * ( (double) tau[gi] + (double) tau[gj] );
			double lambda = lambda_min * ( 1.0 - t ) + lambda_max * t;
			/* Jeong Eq. 8: L°(w_i) = 2/E_i Σ λ_ij (M_i w_j − M_j w_i) / (|l_ij| (M_i + M_j)) */
			double weight = 2.0 / E[i] * lambda / ( l * ( M[gi] + M[gj] ) );
			A[(size_t) i * n + j] -= dt * weight * M[gi];
			A[(size_t) i * n + i] += dt * weight * M[gj];
		}
	}
	sere_status status = sere_dense_ref_solve( A, rhs, w_out + first, n );
	free( A ), free( rhs ), free( E );
	return status;
}
