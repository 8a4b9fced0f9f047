// Model building (Sec. 3): sampling + constrained Delaunay + relaxation + double layer, on the
// Table 1 maple's exact counts. Counter: triangle-layer points per second.
#include "drying/model.h"
#include "read/leafload.h"

#include <benchmark/benchmark.h>

static void BM_ModelBuildMaple( benchmark::State& state )
{
	char err[1024];
	sere_leaf_source leaf;
	if ( sere_leaf_source_load( "data/leaves/maple.leaf", &leaf, err, sizeof( err ) ) != 0 )
	{
		state.SkipWithError( err );
		return;
	}
	sere_build_params params = sere_build_params_default();
	sere_counts_solve( 13197, 51102, &params.point_count, &params.boundary_count );
	params.relax_iterations = static_cast<int32_t>( state.range( 0 ) );
	for ( auto _ : state )
	{
		sere_model model;
		if ( sere_model_build( &leaf.file.shape, &params, &model, nullptr ) != SERE_OK )
		{
			state.SkipWithError( "build failed" );
			break;
		}
		benchmark::DoNotOptimize( model.p.x );
		sere_model_destroy( &model );
	}
	state.counters["points/s"] = benchmark::Counter( static_cast<double>( params.point_count ) * state.iterations(),
													 benchmark::Counter::kIsRate );
	sere_leaf_source_destroy( &leaf );
}
BENCHMARK( BM_ModelBuildMaple )->ArgName( "relax" )->Arg( 0 )->Arg( 4 )->Unit( benchmark::kMillisecond );
