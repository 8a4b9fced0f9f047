#include "cli/cmd_leaf.h"
#include "cli/commands.h"
#include "cli/options.h"
#include "common/io.h"
#include "common/params.h"
#include "drying/model.h"
#include "read/build.h"
#include "solve/pbd.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void model_help( void )
{
	printf( "usage: sere model LEAF [options]\n\n"
			"Builds the triangle-Voronoi double layer of Sec. 3 from LEAF (a .leaf file or an auxiliary PNG)\n"
			"and prints its counts and mesh quality.\n\n"
			"options:\n"
			"  --particles P --springs S  build exactly P particles and S springs (N = P + 2 - (S + 12)/6\n"
			"                             triangle-layer points, B = 3N - P - 2 of them on the outline)\n"
			"  --points N                 N triangle-layer points, B chosen so outline and interior spacing match\n"
			"                             (default 3000); a leaf needs enough for its outline and a point on\n"
			"                             vein (about 80 to 400 for data/leaves); fewer fail, naming a count\n"
			"                             that works\n"
			"  --seed K                   interior sampling seed (default 1)\n"
			"  --preset P                 take h_vein, h_surf, D, masses from a preset (data/presets)\n"
			"  --set key=value            override one parameter (sere run --help lists them)\n"
			"  --json                     print one JSON object instead of text\n" );
}

int sere_cmd_model( int argc, char** argv )
{
	long long particles = -1, springs = -1, points = 3000, seed = 1;
	int json = 0;
	const char* preset = NULL;
	sere_option_list sets = { .count = 0 };
	const sere_option options[] = {
		sere_option_particles( &particles ),
		sere_option_springs( &springs ),
		{ "--points", SERE_OPTION_COUNT, &points, 3, 30000000, NULL },
		{ "--seed", SERE_OPTION_COUNT, &seed, 0, 4294967295.0, NULL },
		sere_option_preset( &preset ),
		sere_option_sets( &sets ),
		sere_option_json( &json ),
	};
	const char* path;
	int code = sere_options_read( "model", argc, argv, options, sizeof( options ) / sizeof( options[0] ), "LEAF", &path,
								  model_help );
	if ( code != SERE_OPTIONS_GO )
	{
		return code;
	}
	sere_sim_params params = sere_sim_params_default();
	if ( !command_params_apply( "model", &params, preset, &sets ) )
	{
		return 2;
	}
	if ( path == NULL )
	{
		fprintf( stderr, "sere model: missing LEAF (a .leaf file or an auxiliary PNG; see sere model --help)\n" );
		return 2;
	}
	if ( !sere_options_counts_paired( "model", particles, springs ) )
	{
		return 2;
	}

	params.seed = (uint32_t) seed;
	sere_model model;
	sere_build_report report;
	char name[128];
	if ( !command_model_build( "model", path, particles, springs, points, &params, &model, &report, name,
							   sizeof( name ) ) )
	{
		return 1;
	}
	/* The constraint coloring the projection uses (Sec. 5.2): colors and batch sizes. */
	sere_pbd* pbd = NULL;
	if ( sere_pbd_create( model.s.a, model.s.b, model.s.count, model.p.count, &pbd ) != SERE_OK )
	{
		fprintf( stderr, "sere model: %s: coloring failed\n", path );
		sere_model_destroy( &model );
		return 1;
	}
	const sere_coloring* coloring = sere_pbd_coloring( pbd );
	if ( json )
	{
		char name_json[6 * sizeof( name )];
		printf(
			"{\"leaf\": \"%s\", \"particles\": %d, \"springs\": %d, \"triangles\": %d, \"triangle_particles\": %d, "
			"\"voronoi_particles\": %d, \"t_springs\": %d, \"v_springs\": %d, \"l_springs\": %d, \"vein_springs\": %d, "
			"\"boundary_vertices\": %d, \"vein_points\": %d, \"interior_points\": %d, \"min_angle_deg\": %.4f, "
			"\"min_angle_free_deg\": %.4f, \"max_aspect\": %.4f, \"spacing\": %.6g, \"area\": %.6g, \"perimeter\": "
			"%.6g}\n",
			sere_json_escape( name_json, sizeof( name_json ), name ), model.p.count, model.s.count,
			model.triangle_count, model.triangle_particles, model.triangle_count, model.t_springs, model.v_springs,
			model.l_springs, model.vein_springs, model.boundary_count, report.vein_points, report.interior_points,
			report.quality.min_angle_deg, report.quality.min_angle_free_deg, report.quality.max_aspect, report.spacing,
			report.area, report.perimeter );
	}
	else
	{
		printf( "%s (%s)\n", name, path );
		printf( "  particles      %8d  (%d triangle + %d Voronoi)\n", model.p.count, model.triangle_particles,
				model.triangle_count );
		printf( "  springs        %8d  (T %d, V %d, L %d; %d on veins)\n", model.s.count, model.t_springs,
				model.v_springs, model.l_springs, model.vein_springs );
		printf( "  triangles      %8d\n", model.triangle_count );
		printf( "  outline points %8d, vein points %d, interior points %d, spacing %.4g\n", model.boundary_count,
				report.vein_points, report.interior_points, report.spacing );
		printf( "  min angle      %8.2f deg (%.2f deg away from the outline and veins), worst aspect %.2f\n",
				report.quality.min_angle_deg, report.quality.min_angle_free_deg, report.quality.max_aspect );
		printf( "  colors         %8d  (batches of %d to %d springs)\n", coloring->color_count, coloring->min_batch,
				coloring->max_batch );
	}
	sere_pbd_destroy( pbd );
	sere_model_destroy( &model );
	return 0;
}
