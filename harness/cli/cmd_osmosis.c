#include "cli/cmd_leaf.h"
#include "cli/commands.h"
#include "cli/options.h"
#include "common/io.h"
#include "common/topo.h"
#include "drying/osmosis.h"
#include "read/build.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void osmosis_help( void )
{
	printf( "usage: sere osmosis LEAF --preset P --steps N [--mode paper|conservative] [--threads T] [--dump DIR]\n\n"
			"Runs the osmotic water flow alone (Sec. 4, Jeong Eq. 3-10) on both layers and prints, per step, the CG\n"
			"iterations, the final relative residual and the total water of each layer.\n\n"
			"options:\n"
			"  --preset P     Table 2 preset (lambda, water rates, masses); --set key=value overrides\n"
			"  --steps N      implicit steps of dt (default 10)\n"
			"  --mode M       paper (Jeong Eq. 8 as written) or conservative (symmetric 4/(E_i+E_j) weights)\n"
			"  --points N     triangle-layer points (default 1500); or --particles P --springs S exactly\n"
			"  --threads T    OpenMP threads bound with hwloc (0: one per core)\n"
			"  --dump DIR     write the last step's T-layer system: A.mtx (SPD matrix), b.mtx, x.mtx (Matrix\n"
			"                 Market) and particles.csv (w, M, tau per particle), to check in any other solver\n" );
}

static int write_mtx_vector( const char* path, const double* v, int32_t n )
{
	sere_atomic_file file;
	FILE* f = sere_atomic_open( &file, path );
	if ( f == NULL )
	{
		return -1;
	}
	fprintf( f, "%%%%MatrixMarket matrix array real general\n%d 1\n", n );
	for ( int32_t i = 0; i < n; ++i )
	{
		fprintf( f, "%.17g\n", v[i] );
	}
	return sere_atomic_commit( &file );
}

static int dump( const char* dir, sere_osmosis* o, const sere_model* model )
{
	if ( sere_dir_create( dir ) != 0 )
	{
		return -1;
	}
	const sere_csr* a = sere_osmosis_matrix( o );
	char path[4096];
	snprintf( path, sizeof( path ), "%s/A.mtx", dir );
	sere_atomic_file file;
	FILE* f = sere_atomic_open( &file, path );
	if ( f == NULL )
	{
		return -1;
	}
	/* Symmetric storage: the lower triangle, 1-based, as Matrix Market wants it. */
	int32_t lower = 0;
	for ( int32_t i = 0; i < a->rows; ++i )
	{
		for ( int32_t k = a->row_ptr[i]; k < a->row_ptr[i + 1]; ++k )
		{
			lower += a->col[k] <= i;
		}
	}
	fprintf(
		f, "%%%%MatrixMarket matrix coordinate real symmetric\n%% sere osmosis: SPD form of Jeong Eq. 9 (T layer)\n" );
	fprintf( f, "%d %d %d\n", a->rows, a->rows, lower );
	for ( int32_t i = 0; i < a->rows; ++i )
	{
		for ( int32_t k = a->row_ptr[i]; k < a->row_ptr[i + 1]; ++k )
		{
			if ( a->col[k] <= i )
			{
				fprintf( f, "%d %d %.17g\n", i + 1, a->col[k] + 1, a->val[k] );
			}
		}
	}
	if ( sere_atomic_commit( &file ) != 0 )
	{
		return -1;
	}
	snprintf( path, sizeof( path ), "%s/b.mtx", dir );
	if ( write_mtx_vector( path, sere_osmosis_rhs( o ), a->rows ) != 0 )
	{
		return -1;
	}
	snprintf( path, sizeof( path ), "%s/x.mtx", dir );
	if ( write_mtx_vector( path, sere_osmosis_solution( o ), a->rows ) != 0 )
	{
		return -1;
	}
	snprintf( path, sizeof( path ), "%s/particles.csv", dir );
	f = sere_atomic_open( &file, path );
	if ( f == NULL )
	{
		return -1;
	}
	fprintf( f, "particle,w,M,tau\n" );
	for ( int32_t i = 0; i < model->triangle_particles; ++i )
	{
		fprintf( f, "%d,%.17g,%.17g,%.9g\n", i, model->p.w[i], model->p.M[i], (double) model->p.tau[i] );
	}
	return sere_atomic_commit( &file );
}

int sere_cmd_osmosis( int argc, char** argv )
{
	const char *preset = NULL, *dump_dir = NULL;
	long long steps = 10, points = 1500, particles = -1, springs = -1, threads = 0;
	int conservative = -1;
	sere_sim_params params = sere_sim_params_default();
	sere_option_list sets = { .count = 0 };
	static const char* const modes[] = { "paper", "conservative", NULL };
	/* in the order of the usage text */
	const sere_option options[] = {
		sere_option_preset( &preset ),
		{ "--steps", SERE_OPTION_COUNT, &steps, 1, 100000000, NULL },
		{ "--mode", SERE_OPTION_CHOICE, &conservative, 0, 0, modes },
		sere_option_threads( &threads ),
		{ "--dump", SERE_OPTION_DIR, &dump_dir, 0, 0, NULL },
		sere_option_sets( &sets ),
		sere_option_points( &points ),
		sere_option_particles( &particles ),
		sere_option_springs( &springs ),
	};
	const char* path;
	int code = sere_options_read( "osmosis", argc, argv, options, sizeof( options ) / sizeof( options[0] ), "LEAF",
								  &path, osmosis_help );
	if ( code != SERE_OPTIONS_GO )
	{
		return code;
	}
	if ( path == NULL )
	{
		fprintf( stderr, "sere osmosis: missing LEAF (see sere osmosis --help)\n" );
		return 2;
	}
	if ( !sere_options_counts_paired( "osmosis", particles, springs ) )
	{
		return 2;
	}
	if ( !command_params_apply( "osmosis", &params, preset, &sets ) )
	{
		return 2;
	}
	if ( conservative >= 0 )
	{
		params.leaf.osmosis.mode = conservative ? SERE_OSMOSIS_CONSERVATIVE : SERE_OSMOSIS_PAPER;
	}
	int bound = sere_topo_bind( (int) threads, NULL );
	sere_model model;
	char name[128];
	if ( !command_model_build( "osmosis", path, particles, springs, points, &params, &model, NULL, name,
							   sizeof( name ) ) )
	{
		return 1;
	}
	sere_osmosis *t_layer = NULL, *v_layer = NULL;
	sere_status status =
		sere_osmosis_create( 0, model.triangle_particles, model.s.a, model.s.b, model.t_springs, &t_layer );
	if ( status == SERE_OK )
	{
		status = sere_osmosis_create( model.triangle_particles, model.triangle_count, model.s.a + model.t_springs,
									  model.s.b + model.t_springs, model.v_springs, &v_layer );
	}
	status = status == SERE_OK ? sere_osmosis_set_threads( t_layer, bound ) : status;
	status = status == SERE_OK ? sere_osmosis_set_threads( v_layer, bound ) : status;
	/* The leaf's osmosis settings at the leaf's time step, solved to the stand-alone solver's own
	 * tolerance (the leaf loosens its CG stop, kernels/drying/leaf.c), at dt as written */
	sere_osmosis_params op = params.leaf.osmosis;
	op.tolerance = sere_osmosis_params_default().tolerance;
	op.dt = sere_params_decimal( params.leaf.dt );
	printf( "%s: %d particles, %s mode, %d threads\nstep  cg_T  residual_T  water_T       cg_V  residual_V  water_V\n",
			name, model.p.count, op.mode == SERE_OSMOSIS_PAPER ? "paper" : "conservative", bound );
	for ( long long step = 1; step <= steps && status == SERE_OK; ++step )
	{
		sere_osmosis_report rt, rv;
		op.water_rate = params.leaf.water_rate_t;
		status = sere_osmosis_step( t_layer, model.p.x, model.p.y, model.p.z, model.p.tau, model.p.M, model.p.w,
									model.p.m, &op, &rt );
		if ( status == SERE_OK )
		{
			op.water_rate = params.leaf.water_rate_v;
			status = sere_osmosis_step( v_layer, model.p.x, model.p.y, model.p.z, model.p.tau, model.p.M, model.p.w,
										model.p.m, &op, &rv );
		}
		if ( status == SERE_OK )
		{
			printf( "%4lld  %4d  %10.3g  %-12.8g  %4d  %10.3g  %-12.8g%s\n", step, rt.iterations, rt.residual,
					rt.water_after, rv.iterations, rv.residual, rv.water_after,
					rt.stopped || rv.stopped ? "  (a dry layer stopped)" : "" );
		}
	}
	if ( status != SERE_OK )
	{
		fprintf( stderr, "sere osmosis: %s\n", sere_status_text( status ) );
	}
	else if ( dump_dir != NULL && dump( dump_dir, t_layer, &model ) != 0 )
	{
		fprintf( stderr, "sere osmosis: cannot write the system to %s\n", dump_dir );
		status = SERE_ERR_ARGUMENT;
	}
	else if ( dump_dir != NULL )
	{
		printf( "T-layer system of the last step: %s/A.mtx, b.mtx, x.mtx, particles.csv\n", dump_dir );
	}
	sere_osmosis_destroy( t_layer );
	sere_osmosis_destroy( v_layer );
	sere_model_destroy( &model );
	return status == SERE_OK ? 0 : 1;
}
