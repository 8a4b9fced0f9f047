// sere-bench: every kernel's benchmarks in one binary, so a ratio (ours / reference / peer)
// can be read from one run. Each bench/*.cc registers its own benchmarks.
#include "common/machine.h"

#include <benchmark/benchmark.h>
#include <omp.h>

#include <string>

// The machine facts of sere's results (harness/common/machine.h) in the report's context, so a saved
// benchmark JSON says what it was measured on. Each benchmark sets its own thread count (its
// threads argument); "threads" here is OpenMP's default, the most any of them may use, and the
// bench does not bind threads (sere table1 and sere run do), so "binding" reads "unbound"
// unless the process was started bound.
static void add_machine_context()
{
	sere_machine machine;
	sere_machine_read( &machine, omp_get_max_threads() );
	char binding[1024];
	sere_machine_binding_text( &machine, binding, sizeof( binding ) );
	benchmark::AddCustomContext( "cpu", machine.cpu );
	benchmark::AddCustomContext( "simd", machine.simd );
	benchmark::AddCustomContext( "threads", std::to_string( machine.threads ) );
	benchmark::AddCustomContext( "binding", binding );
	benchmark::AddCustomContext( "cores", std::to_string( machine.cores ) );
	benchmark::AddCustomContext( "sere_version", machine.version );
	benchmark::AddCustomContext( "commit", machine.commit );
	benchmark::AddCustomContext( "compiler", machine.compiler );
}

int main( int argc, char** argv )
{
	benchmark::Initialize( &argc, argv );
	if ( benchmark::ReportUnrecognizedArguments( argc, argv ) )
	{
		return 1;
	}
	benchmark::AddCustomContext( "sere", "medians over repetitions are the numbers to quote on a shared machine" );
	add_machine_context();
	benchmark::RunSpecifiedBenchmarks();
	benchmark::Shutdown();
	return 0;
}
