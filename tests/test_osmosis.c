#include "drying/model.h"
#include "drying/osmosis.h"
#include "fixture.h"
#include "read/leafload.h"
#include "ref/osmosis_ref.h"
#include "solve/cg.h"

#include <criterion/criterion.h>
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

/* A jittered grid double layer; the T layer is particles [0, N) with springs [0, t_springs);
 * returns N. */
static int32_t grid_model( sere_model* model, int32_t nx, int32_t ny, double width, double height )
{
	sere_test_plane plane;
	sere_test_plane_grid( &plane, nx, ny, width, height, 0.3, 1, 5 );
	sere_layer_params params = sere_layer_params_default();
	cr_assert_eq( sere_model_from_triangles( &plane.mesh, &params, model ), SERE_OK );
	sere_test_plane_free( &plane );
	return model->triangle_particles;
}

/* One osmosis step on the model's particles (Jeong Eq. 9, 10). */
static sere_status model_step( sere_osmosis* o, sere_model* model, const sere_osmosis_params* params,
							   sere_osmosis_report* report )
{
	return sere_osmosis_step( o, model->p.x, model->p.y, model->p.z, model->p.tau, model->p.M, model->p.w, model->p.m,
							  params, report );
}

/* The default osmosis parameters with diffusion λ in [lo, hi]. */
static sere_osmosis_params lambda_params( double lo, double hi )
{
	sere_osmosis_params params = sere_osmosis_params_default();
	params.lambda_min = lo;
	params.lambda_max = hi;
	return params;
}

static void osmosis_free( sere_osmosis* o, sere_model* model )
{
	sere_osmosis_destroy( o );
	sere_model_destroy( model );
}

static sere_osmosis* t_layer( const sere_model* model )
{
	sere_osmosis* o = NULL;
	cr_assert_eq( sere_osmosis_create( 0, model->triangle_particles, model->s.a, model->s.b, model->t_springs, &o ),
				  SERE_OK );
	return o;
}

static double total( const double* w, int32_t first, int32_t count )
{
	double sum = 0.0;
	for ( int32_t i = first; i < first + count; ++i )
	{
		sum += w[i];
	}
	return sum;
}

Test( osmosis, matrix_is_symmetric )
{
	sere_model model;
	grid_model( &model, 14, 9, 1.4, 0.9 );
	sere_osmosis* o = t_layer( &model );
	sere_osmosis_params params = lambda_params( 0.5, 20.0 );
	sere_osmosis_report report;
	cr_assert_eq( model_step( o, &model, &params, &report ), SERE_OK );
	const sere_csr* a = sere_osmosis_matrix( o );
	int32_t n = a->rows;
	double *x = malloc( sizeof( double ) * n ), *y = malloc( sizeof( double ) * n );
	double *ax = malloc( sizeof( double ) * n ), *ay = malloc( sizeof( double ) * n );
	for ( int32_t i = 0; i < n; ++i )
	{
		x[i] = sin( 1.7 * i + 0.3 );
		y[i] = cos( 0.9 * i );
	}
	sere_csr_spmv( a, x, ax, 0 );
	sere_csr_spmv( a, y, ay, 0 );
	double xay = 0.0, yax = 0.0, norm = 0.0;
	for ( int32_t i = 0; i < n; ++i )
	{
		xay += x[i] * ay[i];
		yax += y[i] * ax[i];
		norm += fabs( x[i] * ay[i] ) + fabs( y[i] * ax[i] );
	}
	/* HPCG's symmetry test: |xᵀAy − yᵀAx| at rounding level of the sums (1e-14 of their size). */
	cr_expect_leq( fabs( xay - yax ), 1e-14 * norm );
	/* and entry by entry, exactly: both rows of a spring read its one conductance */
	for ( int32_t i = 0; i < n; ++i )
	{
		for ( int32_t k = a->row_ptr[i]; k < a->row_ptr[i + 1]; ++k )
		{
			int32_t j = a->col[k], m = a->row_ptr[j];
			while ( m < a->row_ptr[j + 1] && a->col[m] != i )
			{
				m += 1;
			}
			cr_assert_lt( m, a->row_ptr[j + 1], "entry (%d, %d) without (%d, %d)", i, j, j, i );
			cr_expect_eq( a->val[k], a->val[m], "a(%d, %d) = %.17g, a(%d, %d) = %.17g", i, j, a->val[k], j, i,
						  a->val[m] );
		}
	}
	free( x ), free( y ), free( ax ), free( ay );
	osmosis_free( o, &model );
}

/* Each bad input names its own cause, and the water is left as it was: a NaN λ is a parameter
 * out of range and a NaN τ a non-finite input (both once reached the conductances and came back
 * as a matrix that is not SPD); a missing report or array and counts past int32_t are refused. */
Test( osmosis, bad_input_names_its_cause )
{
	sere_model model;
	int32_t n = grid_model( &model, 8, 6, 0.8, 0.6 );
	sere_osmosis* o = t_layer( &model );
	double* w0 = malloc( sizeof( double ) * (size_t) model.p.count );
	memcpy( w0, model.p.w, sizeof( double ) * (size_t) model.p.count );
	sere_osmosis_report report;
	sere_osmosis_params params = lambda_params( NAN, 1.0 );
	cr_expect_eq( model_step( o, &model, &params, &report ), SERE_ERR_ARGUMENT );
	params = lambda_params( 0.5, NAN );
	cr_expect_eq( model_step( o, &model, &params, &report ), SERE_ERR_ARGUMENT );
	params = lambda_params( 0.5, 1.0 );
	model.p.tau[n / 2] = NAN;
	cr_expect_eq( model_step( o, &model, &params, &report ), SERE_ERR_NONFINITE );
	model.p.tau[n / 2] = 0.5f;
	cr_expect_eq( memcmp( model.p.w, w0, sizeof( double ) * (size_t) model.p.count ), 0 );
	cr_expect_eq( model_step( o, &model, &params, NULL ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_osmosis_step( o, model.p.x, model.p.y, model.p.z, NULL, model.p.M, model.p.w, model.p.m, &params,
									 &report ),
				  SERE_ERR_ARGUMENT );
	cr_expect_eq( model_step( o, &model, &params, &report ), SERE_OK, "the layer still steps after the refusals" );
	sere_osmosis* none = NULL;
	const int32_t ends[2] = { 0, 1 };
	cr_expect_eq( sere_osmosis_create( 16, INT32_MAX - 8, ends, ends + 1, 1, &none ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_osmosis_create( 0, 1 << 30, ends, ends + 1, 1 << 30, &none ), SERE_ERR_ARGUMENT );
	cr_expect_null( none );
	free( w0 );
	osmosis_free( o, &model );
}

Test( osmosis, matches_literal_eq9 )
{
	sere_model model;
	int32_t n = grid_model( &model, 10, 7, 1.0, 0.7 );
	double* w_ref = malloc( sizeof( double ) * model.p.capacity );
	sere_osmosis* o = t_layer( &model );
	sere_osmosis_params params = lambda_params( 0.3, 40.0 );
	params.dt = 0.05;
	params.water_rate = -0.05;
	params.tolerance = 1e-14;
	/* Unequal water so the flow is not trivial. */
	for ( int32_t i = 0; i < n; ++i )
	{
		model.p.w[i] *= 1.0 + 0.5 * sin( 0.7 * i );
	}
	cr_assert_eq( sere_osmosis_ref_step( 0, n, model.s.a, model.s.b, model.t_springs, model.p.x, model.p.y, model.p.z,
										 model.p.tau, model.p.M, model.p.w, params.dt, params.lambda_min,
										 params.lambda_max, params.water_rate, w_ref ),
				  SERE_OK );
	sere_osmosis_report report;
	cr_assert_eq( model_step( o, &model, &params, &report ), SERE_OK );
	/* w = M c turns the paper's nonsymmetric Jeong Eq. 9 into the SPD form with the same solution;
	 * CG to 1e-14 and a pivoted dense solve agree to 1e-10 relative (the bar). */
	for ( int32_t i = 0; i < n; ++i )
	{
		cr_assert( w_ref[i] > 0.0 );
		cr_assert_leq( fabs( model.p.w[i] - w_ref[i] ), 1e-10 * fabs( w_ref[i] ), "particle %d: %.17g vs %.17g", i,
					   model.p.w[i], w_ref[i] );
		cr_assert_eq( model.p.m[i], model.p.M[i] + model.p.w[i] ); /* Jeong Eq. 10 */
	}
	free( w_ref );
	osmosis_free( o, &model );
}

Test( osmosis, conservative_mode_conserves_water )
{
	sere_model model;
	int32_t n = grid_model( &model, 16, 10, 1.6, 1.0 );
	for ( int32_t i = 0; i < n; ++i )
	{
		model.p.w[i] *= 1.0 + 0.8 * cos( 1.3 * i );
	}
	double before = total( model.p.w, 0, n );
	sere_osmosis* o = t_layer( &model );
	sere_osmosis_params params = sere_osmosis_params_default();
	params.mode = SERE_OSMOSIS_CONSERVATIVE;
	params.water_rate = 0.0;
	params.lambda_min = 1.0;
	params.lambda_max = 50.0;
	params.dt = 0.01;
	params.tolerance = 1e-14;
	sere_osmosis_report report;
	for ( int step = 0; step < 20; ++step )
	{
		cr_assert_eq( model_step( o, &model, &params, &report ), SERE_OK );
	}
	/* Flow only moves water: the row sums telescope, so the total changes only by rounding and
	 * the CG residual (1e-14), well inside the 1e-12. */
	cr_expect_leq( fabs( total( model.p.w, 0, n ) - before ), 1e-12 * before );
	osmosis_free( o, &model );
}

Test( osmosis, fig8_large_lambda_equalizes_concentration )
{
	sere_model model;
	int32_t n = grid_model( &model, 12, 8, 1.2, 0.8 );
	/* Fig. 8b: some particles lose water, so concentrations M/m differ. */
	for ( int32_t i = 0; i < n; i += 3 )
	{
		model.p.w[i] -= 0.2 * model.p.w[i];
	}
	sere_osmosis* o = t_layer( &model );
	sere_osmosis_params params = sere_osmosis_params_default();
	params.mode = SERE_OSMOSIS_CONSERVATIVE;
	params.lambda_min = params.lambda_max = 1e7; /* λ → ∞ (Fig. 8c) */
	params.water_rate = 0.0;
	params.tolerance = 1e-13;
	sere_osmosis_report report;
	cr_assert_eq( model_step( o, &model, &params, &report ), SERE_OK );
	double lo = INFINITY, hi = 0.0;
	for ( int32_t i = 0; i < n; ++i )
	{
		double c = model.p.M[i] / model.p.m[i];
		lo = fmin( lo, c ), hi = fmax( hi, c );
	}
	/* With λΔt ~ 1e4 per unit length the residual spread is O(1/(λΔt)) of the initial one. */
	cr_expect_leq( hi - lo, 1e-4 * hi, "concentration spread %g", hi - lo );
	osmosis_free( o, &model );
}

/* Fig. 9: a rectangle with solute stripes, water supplied at one point, run to equilibrium. */
static void fig9( int osmotic, double* stripe_water )
{
	sere_model model;
	int32_t n = grid_model( &model, 24, 12, 2.0, 1.0 );
	int32_t supply = -1;
	double best = INFINITY;
	for ( int32_t i = 0; i < n; ++i )
	{
		double y = model.p.y[i];
		/* primary stripe (white, 1.0) along the middle, secondary (grey, 0.55) above, rest (black, 0.1) */
		double solute = fabs( y - 0.5 ) < 0.1 ? 1.0 : ( fabs( y - 0.8 ) < 0.1 ? 0.55 : 0.1 );
		model.p.M[i] = osmotic ? solute : 0.5;
		model.p.w[i] = 0.0; /* completely desiccated at the start */
		model.p.tau[i] = 0.0f;
		double d = hypot( model.p.x[i] - 0.0, model.p.y[i] - 0.5 );
		if ( d < best )
		{
			best = d, supply = i;
		}
	}
	sere_osmosis* o = t_layer( &model );
	sere_osmosis_params params = sere_osmosis_params_default();
	params.mode = SERE_OSMOSIS_CONSERVATIVE;
	params.lambda_min = params.lambda_max = 5.0;
	params.water_rate = 0.0;
	params.dt = 0.5;
	params.supply = &supply;
	params.supply_count = 1;
	params.supply_rate = 1.0;
	sere_osmosis_report report;
	for ( int step = 0; step < 60; ++step )
	{
		cr_assert_eq( model_step( o, &model, &params, &report ), SERE_OK );
	}
	double sum[3] = { 0 }, count[3] = { 0 };
	for ( int32_t i = 0; i < n; ++i )
	{
		double y = model.p.y[i];
		int stripe = fabs( y - 0.5 ) < 0.1 ? 0 : ( fabs( y - 0.8 ) < 0.1 ? 1 : 2 );
		sum[stripe] += model.p.w[i];
		count[stripe] += 1;
	}
	for ( int k = 0; k < 3; ++k )
	{
		stripe_water[k] = sum[k] / count[k];
	}
	osmosis_free( o, &model );
}

Test( osmosis, fig9_osmosis_keeps_low_solute_dry_diffusion_equalizes )
{
	double osmotic[3], diffusion[3];
	fig9( 1, osmotic );
	fig9( 0, diffusion );
	/* Osmotic equilibrium is uniform concentration w/M: water follows solute 1.0 : 0.55 : 0.1. */
	cr_expect_gt( osmotic[0], 5.0 * osmotic[2], "white %g black %g", osmotic[0], osmotic[2] );
	cr_expect_gt( osmotic[1], 3.0 * osmotic[2], "grey %g black %g", osmotic[1], osmotic[2] );
	cr_expect_gt( osmotic[0], osmotic[1] );
	/* Plain diffusion (uniform M) spreads water evenly: stripes within 10% of each other. */
	cr_expect_lt( fabs( diffusion[0] - diffusion[2] ), 0.1 * diffusion[0], "%g %g", diffusion[0], diffusion[2] );
}

static double rim_relative_water( double lambda )
{
	sere_model model;
	int32_t n = grid_model( &model, 20, 12, 1.6, 1.0 );
	double* w0 = malloc( sizeof( double ) * n );
	memcpy( w0, model.p.w, sizeof( double ) * n );
	sere_osmosis* o = t_layer( &model );
	sere_osmosis_params params = sere_osmosis_params_default();
	params.lambda_min = params.lambda_max = lambda;
	params.water_rate = -0.1;
	params.dt = 0.05;
	sere_osmosis_report report;
	/* Half dehydrated, as in Fig. 16. */
	while ( total( model.p.w, 0, n ) > 0.5 * total( w0, 0, n ) )
	{
		cr_assert_eq( model_step( o, &model, &params, &report ), SERE_OK );
	}
	double rim = 0.0;
	int32_t count = 0;
	for ( int32_t i = 0; i < n; ++i )
	{
		if ( model.boundary[i] )
		{
			rim += model.p.w[i] / w0[i];
			count += 1;
		}
	}
	free( w0 );
	osmosis_free( o, &model );
	return rim / count;
}

Test( osmosis, fig16_rim_drier_without_flow )
{
	/* τ is high along the vein row through the base and low at the rim, so rim particles are
	 * light and, without flow (λ = 0), lose their water first. λ = 100 refills them. */
	double dry = rim_relative_water( 0.0 );
	double wet = rim_relative_water( 100.0 );
	cr_expect_lt( dry + 0.05, wet, "rim relative water: lambda 0 -> %g, lambda 100 -> %g", dry, wet );
}

Test( osmosis, deterministic_across_threads )
{
	double* result[2];
	for ( int t = 0; t < 2; ++t )
	{
		omp_set_num_threads( t + 1 );
		sere_model model;
		grid_model( &model, 60, 40, 3.0, 2.0 );
		sere_osmosis* o = t_layer( &model );
		sere_osmosis_params params = lambda_params( 0.1, 10.0 );
		sere_osmosis_report report;
		for ( int step = 0; step < 5; ++step )
		{
			cr_assert_eq( model_step( o, &model, &params, &report ), SERE_OK );
		}
		result[t] = malloc( sizeof( double ) * model.triangle_particles );
		memcpy( result[t], model.p.w, sizeof( double ) * model.triangle_particles );
		cr_assert_gt( model.triangle_particles, 2 * SERE_CG_BLOCK ); /* several blocks, so both threads work */
		osmosis_free( o, &model );
	}
	cr_expect_eq( memcmp( result[0], result[1], sizeof( double ) * 61 * 41 ), 0 );
	free( result[0] ), free( result[1] );
	omp_set_num_threads( 2 );
}

/* A small CSR from a dense symmetric matrix. */
static sere_csr dense_csr( const double* dense, int32_t n )
{
	sere_csr a = { n, 0, malloc( sizeof( int32_t ) * ( n + 1 ) ), malloc( sizeof( int32_t ) * n * n ),
				   malloc( sizeof( double ) * n * n ) };
	a.row_ptr[0] = 0;
	for ( int32_t i = 0; i < n; ++i )
	{
		for ( int32_t j = 0; j < n; ++j )
		{
			if ( dense[i * n + j] != 0.0 )
			{
				a.col[a.nnz] = j;
				a.val[a.nnz++] = dense[i * n + j];
			}
		}
		a.row_ptr[i + 1] = a.nnz;
	}
	return a;
}

static void free_csr( sere_csr* a )
{
	free( a->row_ptr ), free( a->col ), free( a->val );
}

/* sere_cg_solve on a CSR matrix: its SELL layout made for this one solve. */
static sere_status solve_csr( sere_cg_workspace* w, const sere_csr* a, const double* b, double* x, double tolerance,
							  int32_t max_iterations, sere_cg_result* result )
{
	sere_sell* sell;
	cr_assert_eq( sere_sell_create( a, SERE_SELL_SIGMA, &sell ), SERE_OK );
	sere_status status = sere_cg_solve( w, sell, b, x, tolerance, max_iterations, result );
	sere_sell_destroy( sell );
	return status;
}

Test( cg, solves_spd_and_rejects_bad_matrices )
{
	/* 1D Laplacian + identity: SPD; exact solution known by construction. */
	enum
	{
		n = 40
	};
	double dense[n * n] = { 0 }, b[n], x[n], expected[n];
	for ( int i = 0; i < n; ++i )
	{
		dense[i * n + i] = 3.0;
		if ( i > 0 )
			dense[i * n + i - 1] = -1.0;
		if ( i + 1 < n )
			dense[i * n + i + 1] = -1.0;
		expected[i] = sin( 0.3 * i );
	}
	for ( int i = 0; i < n; ++i )
	{
		b[i] = 0.0;
		for ( int j = 0; j < n; ++j )
			b[i] += dense[i * n + j] * expected[j];
		x[i] = 0.0;
	}
	sere_csr a = dense_csr( dense, n );
	sere_cg_workspace* w;
	cr_assert_eq( sere_cg_create( n, &w ), SERE_OK );
	sere_cg_result result;
	cr_assert_eq( solve_csr( w, &a, b, x, 1e-12, 200, &result ), SERE_OK );
	for ( int i = 0; i < n; ++i )
	{
		/* condition number ≤ 5: residual 1e-12 bounds the error by ~5e-12 */
		cr_expect_leq( fabs( x[i] - expected[i] ), 1e-10 );
	}
	cr_expect_leq( result.residual, 1e-12 );

	/* Indefinite: a negative diagonal entry. */
	dense[5 * n + 5] = -3.0;
	sere_csr indefinite = dense_csr( dense, n );
	memset( x, 0, sizeof( x ) );
	cr_expect_eq( solve_csr( w, &indefinite, b, x, 1e-12, 200, &result ), SERE_ERR_NOT_SPD );
	/* A row with no diagonal entry stored. */
	dense[5 * n + 5] = 0.0;
	sere_csr no_diagonal = dense_csr( dense, n );
	memset( x, 0, sizeof( x ) );
	cr_expect_eq( solve_csr( w, &no_diagonal, b, x, 1e-12, 200, &result ), SERE_ERR_NOT_SPD );
	dense[5 * n + 5] = 3.0;

	/* Singular: a graph Laplacian (constant null space) with b outside its range. */
	double lap[n * n] = { 0 };
	for ( int i = 0; i + 1 < n; ++i )
	{
		lap[i * n + i] += 1.0, lap[( i + 1 ) * n + i + 1] += 1.0;
		lap[i * n + i + 1] -= 1.0, lap[( i + 1 ) * n + i] -= 1.0;
	}
	sere_csr singular = dense_csr( lap, n );
	for ( int i = 0; i < n; ++i )
	{
		b[i] = 1.0; /* Σ b ≠ 0: no solution */
		x[i] = 0.0;
	}
	sere_status status = solve_csr( w, &singular, b, x, 1e-12, 500, &result );
	cr_expect( status == SERE_ERR_NOT_SPD || status == SERE_ERR_NO_CONVERGE, "status %d", status );
	for ( int i = 0; i < n; ++i )
	{
		cr_expect( isfinite( x[i] ) );
	}

	/* NaN right-hand side. */
	b[3] = NAN;
	cr_expect_eq( solve_csr( w, &a, b, x, 1e-12, 200, &result ), SERE_ERR_NONFINITE );
	b[3] = 1.0;

	/* A NaN or infinite entry of A with finite b and x: the first residual shows it (it once
	 * ended the solve there with SERE_OK and a NaN residual, or NO_CONVERGE for infinity). */
	const double bad_values[2] = { NAN, INFINITY };
	for ( int k = 0; k < 2; ++k )
	{
		dense[7 * n + 8] = dense[8 * n + 7] = bad_values[k];
		sere_csr bad = dense_csr( dense, n );
		memset( x, 0, sizeof( x ) );
		cr_expect_eq( solve_csr( w, &bad, b, x, 1e-12, 200, &result ), SERE_ERR_NONFINITE, "entry %g", bad_values[k] );
		free_csr( &bad );
	}
	dense[7 * n + 8] = dense[8 * n + 7] = -1.0;

	/* No result to write into: refused, as every other argument, by all three solves. */
	cr_expect_eq( solve_csr( w, &a, b, x, 1e-12, 200, NULL ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_cg_solve_sgs( w, NULL, b, x, 1e-12, 200, NULL ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_cg_solve_amg( w, NULL, b, x, 1e-12, 200, NULL ), SERE_ERR_ARGUMENT );

	/* b = 0 gives x = 0 with no iteration. */
	memset( b, 0, sizeof( b ) );
	x[0] = 5.0;
	cr_expect_eq( solve_csr( w, &a, b, x, 1e-12, 200, &result ), SERE_OK );
	cr_expect_eq( x[0], 0.0 );
	cr_expect_eq( result.iterations, 0 );
	sere_cg_destroy( w );
	free_csr( &a ), free_csr( &indefinite ), free_csr( &no_diagonal ), free_csr( &singular );
}

/* An irregular SPD matrix over several blocks: a weighted graph Laplacian (ring plus
 * pseudo-random long edges, so threads read each other's rows) plus a positive diagonal. */
static sere_csr irregular_spd( int32_t n )
{
	enum
	{
		extra = 3
	};
	int32_t max_nnz = n * ( 3 + 2 * extra );
	sere_csr a = { n, 0, malloc( sizeof( int32_t ) * ( n + 1 ) ), malloc( sizeof( int32_t ) * max_nnz ),
				   malloc( sizeof( double ) * max_nnz ) };
	int32_t* degree = calloc( n, sizeof( int32_t ) );
	int32_t( *edges )[2] = malloc( sizeof( int32_t[2] ) * n * ( 1 + extra ) );
	int32_t edge_count = 0;
	uint32_t state = 12345u;
	for ( int32_t i = 0; i < n; ++i )
	{
		edges[edge_count][0] = i, edges[edge_count][1] = ( i + 1 ) % n, ++edge_count;
		for ( int e = 0; e < extra && i % ( e + 2 ) == 0; ++e )
		{
			state = state * 1664525u + 1013904223u;
			int32_t j = (int32_t) ( state % (uint32_t) n );
			if ( j != i && j != ( i + 1 ) % n && ( j + 1 ) % n != i )
			{
				edges[edge_count][0] = i, edges[edge_count][1] = j, ++edge_count;
			}
		}
	}
	/* dense row scratch is fine at test sizes: n ≤ a few thousand */
	double* row = calloc( n, sizeof( double ) );
	int32_t** adjacency = malloc( sizeof( int32_t* ) * n );
	for ( int32_t i = 0; i < n; ++i )
	{
		adjacency[i] = malloc( sizeof( int32_t ) * ( 2 + 2 * extra + 8 ) );
	}
	for ( int32_t e = 0; e < edge_count; ++e )
	{
		int32_t i = edges[e][0], j = edges[e][1];
		adjacency[i][degree[i]++] = j;
		adjacency[j][degree[j]++] = i;
	}
	a.row_ptr[0] = 0;
	for ( int32_t i = 0; i < n; ++i )
	{
		double diagonal = 0.01 * ( 1 + i % 7 );
		for ( int32_t k = 0; k < degree[i]; ++k )
		{
			int32_t j = adjacency[i][k];
			double weight = 0.5 + 0.25 * ( ( i + j ) % 5 );
			row[j] -= weight;
			diagonal += weight;
		}
		row[i] += diagonal;
		for ( int32_t j = 0; j < n; ++j )
		{
			if ( row[j] != 0.0 )
			{
				a.col[a.nnz] = j;
				a.val[a.nnz++] = row[j];
				row[j] = 0.0;
			}
		}
		a.row_ptr[i + 1] = a.nnz;
	}
	for ( int32_t i = 0; i < n; ++i )
	{
		free( adjacency[i] );
	}
	free( adjacency ), free( row ), free( edges ), free( degree );
	return a;
}

Test( cg, bitwise_identical_for_1_2_3_threads )
{
	const int32_t n = 3 * SERE_CG_BLOCK + 77; /* several blocks and a short last one */
	sere_csr a = irregular_spd( n );
	double* b = malloc( sizeof( double ) * n );
	double* x[3];
	sere_cg_result result[3];
	for ( int32_t i = 0; i < n; ++i )
	{
		b[i] = sin( 0.01 * i ) + 0.5;
	}
	sere_cg_workspace* w;
	cr_assert_eq( sere_cg_create( n, &w ), SERE_OK );
	for ( int t = 0; t < 3; ++t )
	{
		omp_set_num_threads( t + 1 );
		x[t] = malloc( sizeof( double ) * n );
		for ( int32_t i = 0; i < n; ++i )
		{
			x[t][i] = 0.1 * cos( 0.02 * i ); /* warm start */
		}
		cr_assert_eq( solve_csr( w, &a, b, x[t], 1e-11, 2000, &result[t] ), SERE_OK );
		cr_expect_leq( result[t].residual, 1e-11 );
	}
	for ( int t = 1; t < 3; ++t )
	{
		cr_expect_eq( result[t].iterations, result[0].iterations );
		cr_expect_eq( memcmp( &result[t].residual, &result[0].residual, sizeof( double ) ), 0 );
		cr_expect_eq( memcmp( x[t], x[0], sizeof( double ) * n ), 0, "%d threads differ from 1", t + 1 );
	}
	/* The solution satisfies A x = b to the tolerance, checked independently. */
	double* ax = malloc( sizeof( double ) * n );
	sere_csr_spmv( &a, x[0], ax, 0 );
	double rr = 0.0, bb = 0.0;
	for ( int32_t i = 0; i < n; ++i )
	{
		rr += ( b[i] - ax[i] ) * ( b[i] - ax[i] );
		bb += b[i] * b[i];
	}
	cr_expect_leq( sqrt( rr / bb ), 2e-11 );
	omp_set_num_threads( 2 );
	sere_cg_destroy( w );
	free( ax ), free( b ), free( x[0] ), free( x[1] ), free( x[2] );
	free_csr( &a );
}

Test( osmosis, extrapolated_start_saves_iterations_not_accuracy )
{
	/* A steadily drying layer with a large λ (the plane tree's 100): one workspace kept across
	 * the steps starts CG from 3 c_n − 3 c_{n−1} + c_{n−2}; the other is made anew every step,
	 * so it starts from c_n, as a first step does. */
	sere_model kept_model, fresh_model;
	grid_model( &kept_model, 60, 40, 3.0, 2.0 );
	grid_model( &fresh_model, 60, 40, 3.0, 2.0 );
	const int32_t n = kept_model.triangle_particles;
	sere_osmosis_params params = sere_osmosis_params_default();
	params.lambda_min = params.lambda_max = 100.0;
	params.water_rate = -0.1;
	sere_osmosis* kept = t_layer( &kept_model );
	sere_osmosis_report kept_report, fresh_report;
	int32_t kept_sum = 0, fresh_sum = 0;
	for ( int step = 0; step < 100; ++step )
	{
		cr_assert_eq( sere_osmosis_step( kept, kept_model.p.x, kept_model.p.y, kept_model.p.z, kept_model.p.tau,
										 kept_model.p.M, kept_model.p.w, kept_model.p.m, &params, &kept_report ),
					  SERE_OK );
		sere_osmosis* fresh = t_layer( &fresh_model );
		cr_assert_eq( sere_osmosis_step( fresh, fresh_model.p.x, fresh_model.p.y, fresh_model.p.z, fresh_model.p.tau,
										 fresh_model.p.M, fresh_model.p.w, fresh_model.p.m, &params, &fresh_report ),
					  SERE_OK );
		sere_osmosis_destroy( fresh );
		kept_sum += kept_report.iterations, fresh_sum += fresh_report.iterations;
	}
	/* Both solve to ‖r‖ ≤ 1e-10 ‖b‖ every step; the two answers differ by at most the errors
	 * those residuals allow, amplified by the conditioning (about 1e3 here): 1e-6 relative to
	 * the largest water content is far above that and far below any physical difference. */
	double worst = 0.0, largest = 0.0;
	for ( int32_t i = 0; i < n; ++i )
	{
		worst = fmax( worst, fabs( kept_model.p.w[i] - fresh_model.p.w[i] ) );
		largest = fmax( largest, fabs( fresh_model.p.w[i] ) );
	}
	cr_expect_leq( worst, 1e-6 * largest, "water differs by %g (largest %g)", worst, largest );
	/* Iteration counts are deterministic, so this is not a timing test. Measured: 2193 against
	 * 6626 iterations over the 100 steps, and 10 against 66 in the last one, when the drying
	 * has become steady (the line through two steps instead of the parabola took 3315, so the
	 * 0.4 bound below also checks that the guess is the parabola); the bounds leave room for
	 * other compilers' rounding. */
	cr_log_info( "extrapolated start: %d iterations in 100 steps (last %d), plain start %d (last %d)", kept_sum,
				 kept_report.iterations, fresh_sum, fresh_report.iterations );
	cr_expect_lt( 10 * kept_sum, 4 * fresh_sum, "extrapolated start: %d iterations in 100 steps, plain start %d",
				  kept_sum, fresh_sum );
	cr_expect_lt( 2 * kept_report.iterations, fresh_report.iterations, "last step: %d vs %d iterations",
				  kept_report.iterations, fresh_report.iterations );
	sere_osmosis_destroy( kept );
	sere_model_destroy( &kept_model );
	sere_model_destroy( &fresh_model );
}

/* A matrix no mesh gives: row lengths from 0 to 300 (empty rows, a few very long ones), columns
 * anywhere and in no particular order, values of both signs. */
static sere_csr ragged_csr( int32_t n, uint32_t seed )
{
	uint32_t state = seed;
	int32_t* length = malloc( sizeof( int32_t ) * n );
	int32_t nnz = 0;
	for ( int32_t i = 0; i < n; ++i )
	{
		state = state * 1664525u + 1013904223u;
		uint32_t pick = ( state >> 8 ) % 100u;
		length[i] = pick < 10 ? 0 : pick < 97 ? (int32_t) ( pick % 13 ) : 100 + (int32_t) ( pick * 2 );
		nnz += length[i];
	}
	sere_csr a = { n, nnz, malloc( sizeof( int32_t ) * ( n + 1 ) ), malloc( sizeof( int32_t ) * nnz ),
				   malloc( sizeof( double ) * nnz ) };
	a.row_ptr[0] = 0;
	for ( int32_t i = 0; i < n; ++i )
	{
		a.row_ptr[i + 1] = a.row_ptr[i] + length[i];
		for ( int32_t k = a.row_ptr[i]; k < a.row_ptr[i + 1]; ++k )
		{
			state = state * 1664525u + 1013904223u;
			a.col[k] = (int32_t) ( ( state >> 4 ) % (uint32_t) n );
			a.val[k] = sin( 0.37 * k + 1.1 * i ) * ( 1.0 + ( k % 5 ) );
		}
	}
	free( length );
	return a;
}

/* y from sere_sell_spmv and from sere_csr_spmv, compared bit for bit at 1, 2 and 3 threads. */
static void expect_sell_equals_csr( const sere_csr* a, const sere_sell* sell, const double* x, const char* what )
{
	double *y_csr = malloc( sizeof( double ) * a->rows ), *y_sell = malloc( sizeof( double ) * a->rows );
	for ( int t = 1; t <= 3; ++t )
	{
		omp_set_num_threads( t );
		sere_csr_spmv( a, x, y_csr, 0 );
		memset( y_sell, 0xff, sizeof( double ) * a->rows ); /* NaN: a row SELL forgot would show */
		sere_sell_spmv( sell, x, y_sell );
		int32_t first = -1;
		for ( int32_t i = 0; i < a->rows && first < 0; ++i )
		{
			first = memcmp( &y_csr[i], &y_sell[i], sizeof( double ) ) != 0 ? i : -1;
		}
		cr_expect_eq( first, -1, "%s, sigma %d, %d threads: row %d: CSR %.17g, SELL %.17g", what, sell->sigma, t, first,
					  first >= 0 ? y_csr[first] : 0.0, first >= 0 ? y_sell[first] : 0.0 );
	}
	omp_set_num_threads( 2 );
	free( y_csr ), free( y_sell );
}

Test( cg, sell_spmv_bitwise_equals_csr_on_ragged_rows )
{
	const int32_t n = 3 * SERE_CG_BLOCK + 77; /* a short last window and a short last chunk */
	sere_csr a = ragged_csr( n, 777u );
	int32_t empty = 0, longest = 0;
	for ( int32_t i = 0; i < n; ++i )
	{
		int32_t length = a.row_ptr[i + 1] - a.row_ptr[i];
		empty += length == 0;
		longest = length > longest ? length : longest;
	}
	cr_assert_gt( empty, 50 );
	cr_assert_gt( longest, 250 );
	double* x = malloc( sizeof( double ) * n );
	for ( int32_t i = 0; i < n; ++i )
	{
		x[i] = i % 11 == 0 ? 0.0 : cos( 0.7 * i ) * ( i % 3 == 0 ? -1e3 : 1e-3 );
	}
	const int32_t sigmas[] = { SERE_SELL_C, SERE_SELL_SIGMA, SERE_CG_BLOCK };
	for ( int k = 0; k < 3; ++k )
	{
		sere_sell* sell;
		cr_assert_eq( sere_sell_create( &a, sigmas[k], &sell ), SERE_OK );
		expect_sell_equals_csr( &a, sell, x, "ragged" );
		/* New values through the kept layout give what a fresh layout gives. */
		for ( int32_t e = 0; e < a.nnz; ++e )
		{
			a.val[e] = -0.5 * a.val[e] + 1e-3 * e;
		}
		cr_assert_eq( sere_sell_update( sell, &a ), SERE_OK );
		expect_sell_equals_csr( &a, sell, x, "ragged, updated" );
		sere_sell_destroy( sell );
	}
	/* A changed pattern is refused, not silently multiplied. */
	sere_sell* sell;
	cr_assert_eq( sere_sell_create( &a, SERE_SELL_SIGMA, &sell ), SERE_OK );
	int32_t last = a.nnz - 1;
	a.col[last] = ( a.col[last] + 1 ) % n;
	cr_expect_eq( sere_sell_update( sell, &a ), SERE_ERR_ARGUMENT );
	sere_sell_destroy( sell );
	/* A diagonal entry stored twice is refused: the CG reads one slot per diagonal. */
	int32_t row = 0;
	while ( a.row_ptr[row + 1] - a.row_ptr[row] < 2 )
	{
		row += 1;
	}
	a.col[a.row_ptr[row]] = row;
	a.col[a.row_ptr[row] + 1] = row;
	cr_expect_eq( sere_sell_create( &a, SERE_SELL_SIGMA, &sell ), SERE_ERR_ARGUMENT );
	/* σ must be a multiple of SERE_SELL_C dividing SERE_CG_BLOCK. */
	cr_expect_eq( sere_sell_create( &a, 12, &sell ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_sell_create( &a, 4, &sell ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_sell_create( &a, 2 * SERE_CG_BLOCK, &sell ), SERE_ERR_ARGUMENT );
	free( x );
	free_csr( &a );
}

/* The Table 1 maple's T (layer 0) and V (layer 1) osmosis systems as bench_cg.cc times them:
 * the leaf at rest, maple-green's λ = 0.04, one step assembled. */
typedef struct maple_system
{
	sere_osmosis* osmosis;
	double* b;
} maple_system;

static void maple_systems( sere_model* model, maple_system systems[2] )
{
	char err[1024];
	sere_leaf_source leaf;
	cr_assert_eq( sere_leaf_source_load( "data/leaves/maple.leaf", &leaf, err, sizeof( err ) ), 0, "%s", err );
	sere_build_params params = sere_build_params_default();
	cr_assert_eq( sere_counts_solve( 13197, 51102, &params.point_count, &params.boundary_count ), SERE_OK );
	cr_assert_eq( sere_model_build( &leaf.file.shape, &params, model, NULL ), SERE_OK );
	sere_leaf_source_destroy( &leaf );
	double* w = malloc( sizeof( double ) * model->p.count );
	double* mass = malloc( sizeof( double ) * model->p.count );
	for ( int layer = 0; layer < 2; ++layer )
	{
		int32_t first = layer == 0 ? 0 : model->triangle_particles;
		int32_t count = layer == 0 ? model->triangle_particles : model->triangle_count;
		int32_t s0 = layer == 0 ? 0 : model->t_springs;
		int32_t sc = layer == 0 ? model->t_springs : model->v_springs;
		cr_assert_eq(
			sere_osmosis_create( first, count, model->s.a + s0, model->s.b + s0, sc, &systems[layer].osmosis ),
			SERE_OK );
		memcpy( w, model->p.w, sizeof( double ) * model->p.count );
		memcpy( mass, model->p.m, sizeof( double ) * model->p.count );
		sere_osmosis_params osmosis = sere_osmosis_params_default();
		osmosis.lambda_min = osmosis.lambda_max = 0.04;
		sere_osmosis_report report;
		cr_assert_eq( sere_osmosis_step( systems[layer].osmosis, model->p.x, model->p.y, model->p.z, model->p.tau,
										 model->p.M, w, mass, &osmosis, &report ),
					  SERE_OK );
		systems[layer].b = malloc( sizeof( double ) * count );
		memcpy( systems[layer].b, sere_osmosis_rhs( systems[layer].osmosis ), sizeof( double ) * count );
	}
	free( w ), free( mass );
}

/* Jacobi PCG exactly as the textbook (and sere before its SELL version) writes it: serial,
 * q = A p by CSR, every sum a plain loop, three sweeps per iteration. */
static int32_t textbook_pcg( const sere_csr* a, const double* b, double* x, double tolerance, int32_t cap,
							 double* residual )
{
	int32_t n = a->rows;
	double *r = malloc( sizeof( double ) * n ), *z = malloc( sizeof( double ) * n );
	double *p = malloc( sizeof( double ) * n ), *q = malloc( sizeof( double ) * n );
	double *d = malloc( sizeof( double ) * n ), bb = 0.0, rz = 0.0, rr = 0.0;
	sere_csr_spmv( a, x, q, 0 );
	for ( int32_t i = 0; i < n; ++i )
	{
		d[i] = 0.0;
		for ( int32_t k = a->row_ptr[i]; k < a->row_ptr[i + 1]; ++k )
		{
			d[i] += a->col[k] == i ? a->val[k] : 0.0;
		}
		r[i] = b[i] - q[i];
		z[i] = r[i] / d[i];
		p[i] = z[i];
		bb += b[i] * b[i], rz += r[i] * z[i], rr += r[i] * r[i];
	}
	int32_t it = 0;
	*residual = sqrt( rr / bb );
	while ( *residual > tolerance && it < cap )
	{
		sere_csr_spmv( a, p, q, 0 );
		double pq = 0.0;
		for ( int32_t i = 0; i < n; ++i )
		{
			pq += p[i] * q[i];
		}
		double alpha = rz / pq, rz_new = 0.0;
		rr = 0.0;
		for ( int32_t i = 0; i < n; ++i )
		{
			x[i] += alpha * p[i];
			r[i] -= alpha * q[i];
			z[i] = r[i] / d[i];
			rz_new += r[i] * z[i], rr += r[i] * r[i];
		}
		it += 1;
		*residual = sqrt( rr / bb );
		double beta = rz_new / rz;
		rz = rz_new;
		for ( int32_t i = 0; i < n; ++i )
		{
			p[i] = z[i] + beta * p[i];
		}
	}
	free( r ), free( z ), free( p ), free( q ), free( d );
	return it;
}

Test( cg, maple_systems_sell_and_two_barrier_cg, .timeout = 120 )
{
	sere_model model;
	maple_system systems[2];
	maple_systems( &model, systems );
	const char* names[2] = { "T", "V" };
	for ( int layer = 0; layer < 2; ++layer )
	{
		const sere_csr* a = sere_osmosis_matrix( systems[layer].osmosis );
		const int32_t n = a->rows;
		double* x = malloc( sizeof( double ) * n );
		for ( int32_t i = 0; i < n; ++i )
		{
			x[i] = 1.0 + 0.5 * sin( 0.013 * i ) - ( i % 7 == 0 ? 2.0 : 0.0 );
		}
		const int32_t sigmas[] = { SERE_SELL_C, SERE_SELL_SIGMA, SERE_CG_BLOCK };
		for ( int k = 0; k < 3; ++k )
		{
			sere_sell* sell;
			cr_assert_eq( sere_sell_create( a, sigmas[k], &sell ), SERE_OK );
			expect_sell_equals_csr( a, sell, x, names[layer] );
			sere_sell_destroy( sell );
		}

		sere_sell* sell;
		cr_assert_eq( sere_sell_create( a, SERE_SELL_SIGMA, &sell ), SERE_OK );
		sere_cg_workspace* w;
		cr_assert_eq( sere_cg_create( n, &w ), SERE_OK );
		double *ours = malloc( sizeof( double ) * n ), *textbook = malloc( sizeof( double ) * n );
		const double tolerances[2] = { 1e-8, 1e-12 };
		for ( int k = 0; k < 2; ++k )
		{
			double residual;
			memset( textbook, 0, sizeof( double ) * n );
			int32_t textbook_iterations = textbook_pcg( a, systems[layer].b, textbook, tolerances[k], 1000, &residual );
			for ( int t = 1; t <= 3; ++t )
			{
				omp_set_num_threads( t );
				memset( x, 0, sizeof( double ) * n );
				sere_cg_result result;
				cr_assert_eq( sere_cg_solve( w, sell, systems[layer].b, x, tolerances[k], 1000, &result ), SERE_OK );
				if ( t == 1 )
				{
					memcpy( ours, x, sizeof( double ) * n );
					/* The same recurrence; only the order in which pᵀq, rᵀz and rᵀr are summed
					 * differs, which perturbs each iterate at rounding level (1e-16 relative), and
					 * the few dozen iterations here do not amplify that much. Measured on the
					 * maple: the same iteration counts, residuals equal to 6 digits, x equal to
					 * 2e-15 of its largest entry. The bounds leave 3 orders of magnitude for
					 * other compilers and still lie far below what a changed algorithm (another
					 * recurrence, a lost iteration) would give: about the tolerance itself. */
					cr_expect_eq( result.iterations, textbook_iterations,
								  "%s, tolerance %g: %d iterations, textbook %d", names[layer], tolerances[k],
								  result.iterations, textbook_iterations );
					cr_expect_leq( fabs( result.residual - residual ), 1e-3 * residual,
								   "%s, tolerance %g: residual %g, textbook %g", names[layer], tolerances[k],
								   result.residual, residual );
					double worst = 0.0, largest = 0.0;
					for ( int32_t i = 0; i < n; ++i )
					{
						worst = fmax( worst, fabs( x[i] - textbook[i] ) );
						largest = fmax( largest, fabs( textbook[i] ) );
					}
					cr_expect_leq( worst, 1e-12 * largest, "%s, tolerance %g: x differs by %g of %g", names[layer],
								   tolerances[k], worst, largest );
				}
				else
				{
					cr_expect_eq( memcmp( x, ours, sizeof( double ) * n ), 0, "%s: %d threads differ from 1",
								  names[layer], t );
				}
			}
		}
		omp_set_num_threads( 2 );
		free( x ), free( ours ), free( textbook );
		sere_cg_destroy( w );
		sere_sell_destroy( sell );
		sere_osmosis_destroy( systems[layer].osmosis );
		free( systems[layer].b );
	}
	sere_model_destroy( &model );
}
