// sere-bench: every kernel's benchmarks in one binary, so a ratio (ours / reference / peer)
// can be read from one run. Each bench/*.cc registers its own benchmarks.
#include <benchmark/benchmark.h>

int main( int argc, char** argv )
{
	benchmark::Initialize( &argc, argv );
	if ( benchmark::ReportUnrecognizedArguments( argc, argv ) )
	{
		return 1;
	}
	benchmark::AddCustomContext( "sere", "medians over repetitions are the numbers to quote on a shared machine" );
	benchmark::RunSpecifiedBenchmarks();
	benchmark::Shutdown();
	return 0;
}
