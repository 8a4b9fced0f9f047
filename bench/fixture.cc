#include "fixture.h"

#include "leafload.h"

#include <cstdio>
#include <cstdlib>

namespace
{
struct table1_leaf
{
	const char* path;
	long long particles;
	long long springs;
};

const table1_leaf leaves[3] = {
	{ "data/leaves/maple.leaf", 13197, 51102 },
	{ "data/leaves/plane.leaf", 15069, 59550 },
	{ "data/leaves/wisteria.leaf", 12750, 50436 },
};

sere_model models[3];
bool built[3];
} // namespace

const sere_model* sere_bench_model( sere_bench_leaf which )
{
	int k = static_cast<int>( which );
	if ( built[k] )
	{
		return &models[k];
	}
	char err[1024];
	sere_leaf leaf;
	if ( sere_leaf_load( leaves[k].path, &leaf, err, sizeof( err ) ) != 0 )
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
	sere_leaf_free( &leaf );
	if ( status != SERE_OK )
	{
		std::fprintf( stderr, "sere-bench: %s: %s\n", leaves[k].path, sere_status_text( status ) );
		std::exit( 1 );
	}
	built[k] = true;
	return &models[k];
}
