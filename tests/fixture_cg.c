/* Osmosis systems for the conjugate gradient tests (fixture_cg.h). */
#include "fixture_cg.h"

#include "fixture.h"

#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

double* sere_test_v_system( sere_model* model, int32_t nx, int32_t ny, double lambda, sere_osmosis** o,
							sere_osmosis_report* report )
{
	sere_test_plane plane;
	sere_test_plane_grid( &plane, nx, ny, 1.0 * nx / 10, 1.0 * ny / 10, 0.3, 1, 5 );
	sere_layer_params layer = sere_layer_params_default();
	cr_assert_eq( sere_model_from_triangles( &plane.mesh, &layer, model ), SERE_OK );
	sere_test_plane_free( &plane );
	cr_assert_eq( sere_osmosis_create( model->triangle_particles, model->triangle_count, model->s.a + model->t_springs,
									   model->s.b + model->t_springs, model->v_springs, o ),
				  SERE_OK );
	sere_osmosis_params params = sere_osmosis_params_default();
	params.lambda_min = params.lambda_max = lambda;
	cr_assert_eq( sere_osmosis_step( *o, model->p.x, model->p.y, model->p.z, model->p.tau, model->p.M, model->p.w,
									 model->p.m, &params, report ),
				  SERE_OK );
	int32_t n = model->triangle_count;
	double* b = malloc( sizeof( double ) * n );
	memcpy( b, sere_osmosis_rhs( *o ), sizeof( double ) * n );
	return b;
}

void sere_test_cg_system_make( sere_test_cg_system* s, int32_t nx, int32_t ny )
{
	s->b = sere_test_v_system( &s->model, nx, ny, 100.0, &s->o, &s->report );
	s->a = sere_osmosis_matrix( s->o );
	s->n = s->a->rows;
	cr_assert_eq( sere_sgs_create( s->a, &s->g ), SERE_OK );
}

void sere_test_cg_system_free( sere_test_cg_system* s )
{
	sere_sgs_destroy( s->g );
	sere_osmosis_destroy( s->o );
	sere_model_destroy( &s->model );
	free( s->b );
}

double sere_test_relative_residual( const sere_csr* a, const double* b, const double* x )
{
	double* ax = malloc( sizeof( double ) * a->rows );
	sere_csr_spmv( a, x, ax, 0 );
	double rr = 0.0, bb = 0.0;
	for ( int32_t i = 0; i < a->rows; ++i )
	{
		rr += ( b[i] - ax[i] ) * ( b[i] - ax[i] );
		bb += b[i] * b[i];
	}
	free( ax );
	return sqrt( rr / bb );
}

double sere_test_worst_difference( const double* x, const double* reference, int32_t n, double* largest )
{
	double worst = 0.0;
	*largest = 0.0;
	for ( int32_t i = 0; i < n; ++i )
	{
		worst = fmax( worst, fabs( x[i] - reference[i] ) );
		*largest = fmax( *largest, fabs( reference[i] ) );
	}
	return worst;
}

double sere_test_symmetry( const double* x, const double* y, const double* bx, const double* by, int32_t n, double* gap,
						   double* norm )
{
	double xby = 0.0, ybx = 0.0, xbx = 0.0;
	*norm = 0.0;
	for ( int32_t i = 0; i < n; ++i )
	{
		xby += x[i] * by[i];
		ybx += y[i] * bx[i];
		xbx += x[i] * bx[i];
		*norm += fabs( x[i] * by[i] ) + fabs( y[i] * bx[i] );
	}
	*gap = xby - ybx;
	return xbx;
}
