#include "fixture.h"

#include "drying/leaf.h"
#include "read/build.h"
#include "read/leafload.h"

#include <cstdio>
#include <cstdlib>

namespace
{
struct table1_leaf
{
	const char* path;
	long long particles;
	long long springs;
	const char* preset;
};

const table1_leaf leaves[3] = {
	{ "data/leaves/maple.leaf", 13197, 51102, "maple-green" },
	{ "data/leaves/plane.leaf", 15069, 59550, "plane-tree" },
	{ "data/leaves/wisteria.leaf", 12750, 50436, "wisteria" },
};

sere_model models[3];
bool built[3];
sere_model dried[3];
int dried_frames[3];
} // namespace

const sere_model* sere_bench_model( sere_bench_leaf which )
{
	int k = static_cast<int>( which );
	if ( built[k] )
	{
		return &models[k];
	}
	char err[1024];
	sere_leaf_source leaf;
	if ( sere_leaf_source_load( leaves[k].path, &leaf, err, sizeof( err ) ) != 0 )
	{
		std::fprintf( stderr, "sere-bench: %s (run from the repository root)\n", err );
		std::exit( 1 );
	}
	sere_build_params params = sere_build_params_default();
	if ( sere_counts_solve( leaves[k].particles, leaves[k].springs, &params.point_count, &params.boundary_count ) !=
		 SERE_OK )
	{
		std::fprintf( stderr, "sere-bench: bad Table 1 counts\n" );
		std::exit( 1 );
	}
	sere_status status = sere_model_build( &leaf.file.shape, &params, &models[k], nullptr );
	sere_leaf_source_destroy( &leaf );
	if ( status != SERE_OK )
	{
		std::fprintf( stderr, "sere-bench: %s: %s\n", leaves[k].path, sere_status_text( status ) );
		std::exit( 1 );
	}
	built[k] = true;
	return &models[k];
}

const sere_model* sere_bench_dried_model( sere_bench_leaf which, int frames )
{
	int k = static_cast<int>( which );
	if ( dried_frames[k] == frames )
	{
		return &dried[k];
	}
	if ( dried_frames[k] != 0 )
	{
		sere_model_destroy( &dried[k] );
		dried_frames[k] = 0;
	}
	std::fprintf( stderr, "sere-bench: drying %s for %d frames (preset %s) for the dried scenes\n", leaves[k].path,
				  frames, leaves[k].preset );
	char err[1024], name[128];
	sere_sim_params params = sere_sim_params_default();
	sere_build_report report;
	if ( sere_params_load_preset( &params, leaves[k].preset, err, sizeof( err ) ) != 0 ||
		 sere_harness_build( leaves[k].path, leaves[k].particles, leaves[k].springs, 0, &params, &dried[k], &report,
							 name, sizeof( name ), err, sizeof( err ) ) != 0 )
	{
		std::fprintf( stderr, "sere-bench: %s (run from the repository root)\n", err );
		std::exit( 1 );
	}
	sere_leaf_sim* sim = nullptr;
	sere_status status = sere_leaf_create( &dried[k], &sim );
	const sere_leaf_params& leaf = params.leaf;
	sere_leaf_stats stats;
	for ( int f = 0; f < frames && status == SERE_OK; ++f )
	{
		status = sere_leaf_step( sim, &leaf, &stats );
	}
	sere_leaf_destroy( sim );
	if ( status != SERE_OK )
	{
		std::fprintf( stderr, "sere-bench: drying %s: %s\n", leaves[k].path, sere_status_text( status ) );
		std::exit( 1 );
	}
	dried_frames[k] = frames;
	return &dried[k];
}

std::vector<float> sere_bench_frustrated_rest( const sere_model* model )
{
	std::vector<float> rest( model->s.rest, model->s.rest + model->s.count );
	for ( int32_t k = 0; k < model->s.count; ++k )
	{
		rest[k] *= ( model->s.kind[k] & SERE_SPRING_LAYER_MASK ) == SERE_SPRING_V ? 0.9f : 1.0f;
	}
	return rest;
}
