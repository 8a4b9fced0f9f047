// One day of the seed-002 Markov chain of leaf states (kernels/season/markov.h, Sec. 5, Tang Eq. 5-6) on a
// tree of 10^6 leaves: sere_markov_advance at 1 and 2 threads (it parallelizes inside: an OpenMP
// static schedule over blocks of 2048 leaves, each block a vectorized stepping loop then a
// histogram) and, separately, sere_markov_day_prepare, the once-a-day cost of turning the day's
// weather into sampling tables. Goal: a whole tree's day in a few milliseconds, nothing beside the
// per-leaf mass-spring and rendering work, and 2 threads near 2x.
//
// The chain: 8 (texture, deformation level) states shaped like the season chains
// (data/seasons/maple.chain, tests/test_markov.c): green/0 -> yellow/1 or red/1 -> yellow/2 or
// red/2 -> brown/2 -> brown/3 (withered) -> fallen, with shortcuts to brown; a cool damp autumn
// day (10 C, humidity 0.6).
//
// Every iteration advances the same population by the same day: the 1 MB of states is copied back
// from a saved population with the timer paused (with the kernel's static schedule, so each thread
// finds its share in its own cache), so every iteration draws the same numbers and writes the same
// states. Letting the population run on would empty the chain into its absorbing state, all leaves
// in one histogram bin. The saved population is the one after 30 such days from all green: every
// state occupied (33% green, 9% fallen, the counters green and fallen).
//
// Counters: leaves/s = leaves x days / wall time; GB/s = the state bytes read and written, 2 per
// leaf per day (the random numbers are computed, not loaded; the tables are 16 KB).
//
// Measured (medians of 5 repetitions, 2-core shared machine, quiet): 1 thread 2.38 ms (420M
// leaves/s), 2 threads 1.22 ms (813-822M leaves/s), 1.96x. 0.84 GB/s at 1 thread: compute-bound,
// about 2.4 ns a leaf for the counter-based random number (three 64-bit multiplies), seven
// threshold compares and the histogram. A day's tables cost 0.3 us. BM_MarkovFloor, the same bytes
// read and written on the same schedule, takes 10.0-10.4 us at 1 thread (the population stays in
// cache): the day is about 200x its memory floor.
#include "season/markov.h"

#include <benchmark/benchmark.h>
#include <omp.h>

#include <cstdlib>
#include <cstring>
#include <vector>

namespace
{
constexpr int64_t leaves = 1000000;
constexpr uint64_t seed = 2024;
constexpr double temperature = 10.0;
constexpr double humidity = 0.6;
constexpr int64_t settle_days = 30;
// The kernel's block of leaves (markov.c): the restore copies block by block with the same
// static schedule.
constexpr int64_t block = 2048;

enum
{
	GREEN0,
	YELLOW1,
	RED1,
	YELLOW2,
	RED2,
	BROWN2,
	WITHERED3,
	FALLEN,
	STATES
};

// P_ii at the corners wet-cold, wet-warm, dry-cold, dry-warm (Tang Eq. 5).
const double stay[STATES * 4] = {
	0.955, 0.9995, 0.935, 0.998, // green, level 0
	0.93,  0.99,   0.91,  0.985, // yellow, level 1
	0.93,  0.99,   0.90,  0.985, // red, level 1
	0.92,  0.985,  0.90,  0.98,	 // yellow, level 2
	0.92,  0.985,  0.89,  0.98,	 // red, level 2
	0.90,  0.98,   0.88,  0.97,	 // brown, level 2
	0.85,  0.97,   0.80,  0.95,	 // withered, level 3
	1.0,   1.0,	   1.0,	  1.0,	 // fallen: absorbing
};

// g_ij at the same corners (Tang Eq. 6): yellow comes with wet weather, red with dry.
const sere_markov_transition transitions[] = {
	{ GREEN0, YELLOW1, { 0.8, 0.7, 0.3, 0.4 } },   { GREEN0, RED1, { 0.2, 0.3, 0.7, 0.6 } },
	{ YELLOW1, YELLOW2, { 0.8, 0.8, 0.6, 0.6 } },  { YELLOW1, BROWN2, { 0.2, 0.2, 0.4, 0.4 } },
	{ RED1, RED2, { 0.8, 0.8, 0.7, 0.7 } },		   { RED1, BROWN2, { 0.2, 0.2, 0.3, 0.3 } },
	{ YELLOW2, BROWN2, { 1, 1, 1, 1 } },		   { RED2, BROWN2, { 1, 1, 1, 1 } },
	{ BROWN2, WITHERED3, { 0.7, 0.6, 0.8, 0.8 } }, { BROWN2, FALLEN, { 0.3, 0.4, 0.2, 0.2 } },
	{ WITHERED3, FALLEN, { 1, 1, 1, 1 } },
};

sere_markov_chain autumn_chain()
{
	sere_markov_chain c{};
	c.state_count = STATES;
	c.stay = stay;
	c.transition_count = static_cast<int32_t>( sizeof( transitions ) / sizeof( transitions[0] ) );
	c.transitions = transitions;
	c.cold = 2.0, c.warm = 24.0;
	c.dry = 0.35, c.wet = 0.85;
	return c;
}

struct tree
{
	sere_markov_day day{};
	std::vector<uint8_t> saved, states;
};

tree& population()
{
	static tree t;
	if ( !t.saved.empty() )
	{
		return t;
	}
	sere_markov_chain chain = autumn_chain();
	if ( sere_markov_validate( &chain ) != SERE_OK ||
		 sere_markov_day_prepare( &chain, temperature, humidity, &t.day ) != SERE_OK )
	{
		std::abort();
	}
	t.states.assign( leaves, GREEN0 );
	for ( int64_t d = 0; d < settle_days; ++d )
	{
		if ( sere_markov_advance( &t.day, t.states.data(), leaves, 0, seed, d, nullptr, 0 ) != SERE_OK )
		{
			std::abort();
		}
	}
	t.saved = t.states;
	return t;
}

void restore( tree& t )
{
	const int64_t blocks = ( leaves + block - 1 ) / block;
	const uint8_t* from = t.saved.data();
	uint8_t* to = t.states.data();
#pragma omp parallel for schedule( static )
	for ( int64_t b = 0; b < blocks; ++b )
	{
		const int64_t first = b * block;
		std::memcpy( to + first, from + first, static_cast<size_t>( leaves - first < block ? leaves - first : block ) );
	}
}

void BM_MarkovAdvance( benchmark::State& state )
{
	const int saved = omp_get_max_threads();
	omp_set_num_threads( static_cast<int>( state.range( 0 ) ) );
	tree& t = population();
	int64_t counts[STATES];
	for ( auto _ : state )
	{
		state.PauseTiming();
		restore( t );
		state.ResumeTiming();
		sere_status status = sere_markov_advance( &t.day, t.states.data(), leaves, 0, seed, settle_days, counts,
												  static_cast<int32_t>( state.range( 0 ) ) );
		benchmark::ClobberMemory();
		if ( status != SERE_OK )
		{
			state.SkipWithError( sere_status_text( status ) );
			break;
		}
	}
	const double done = static_cast<double>( state.iterations() ) * leaves;
	state.counters["leaves/s"] = benchmark::Counter( done, benchmark::Counter::kIsRate );
	state.counters["GB/s"] = benchmark::Counter( 2.0 * done * 1e-9, benchmark::Counter::kIsRate );
	state.counters["fallen"] = static_cast<double>( counts[FALLEN] ) / leaves;
	state.counters["green"] = static_cast<double>( counts[GREEN0] ) / leaves;
	omp_set_num_threads( saved );
}

// The floor of BM_MarkovAdvance: the same state bytes read and written, block by block with the
// kernel's static schedule, each plus a zero the compiler cannot see (so the loads and stores stay);
// no random numbers, thresholds or histogram. The same restore runs outside the timed region.
void BM_MarkovFloor( benchmark::State& state )
{
	const int threads = static_cast<int>( state.range( 0 ) );
	tree& t = population();
	const int64_t blocks = ( leaves + block - 1 ) / block;
	volatile uint8_t opaque_zero = 0;
	for ( auto _ : state )
	{
		state.PauseTiming();
		restore( t );
		const uint8_t zero = opaque_zero;
		uint8_t* states = t.states.data();
		state.ResumeTiming();
#pragma omp parallel for schedule( static ) num_threads( threads )
		for ( int64_t b = 0; b < blocks; ++b )
		{
			const int64_t first = b * block, last = first + block < leaves ? first + block : leaves;
			for ( int64_t i = first; i < last; ++i )
			{
				states[i] = static_cast<uint8_t>( states[i] + zero );
			}
		}
		benchmark::ClobberMemory();
	}
	const double done = static_cast<double>( state.iterations() ) * leaves;
	state.counters["leaves/s"] = benchmark::Counter( done, benchmark::Counter::kIsRate );
	state.counters["GB/s"] = benchmark::Counter( 2.0 * done * 1e-9, benchmark::Counter::kIsRate );
}

// The day's sampling tables from the weather (Tang Eq. 5-6 for every state, then 256 x 8 thresholds
// and targets): once a day for the whole tree.
void BM_MarkovDayPrepare( benchmark::State& state )
{
	sere_markov_chain chain = autumn_chain();
	sere_markov_day day;
	for ( auto _ : state )
	{
		sere_markov_day_prepare( &chain, temperature, humidity, &day );
		benchmark::DoNotOptimize( &day );
		benchmark::ClobberMemory();
	}
}
} // namespace

BENCHMARK( BM_MarkovAdvance )->ArgName( "threads" )->Arg( 1 )->Arg( 2 )->UseRealTime()->Unit( benchmark::kMicrosecond );
BENCHMARK( BM_MarkovFloor )->ArgName( "threads" )->Arg( 1 )->Arg( 2 )->UseRealTime()->Unit( benchmark::kMicrosecond );
BENCHMARK( BM_MarkovDayPrepare )->Unit( benchmark::kMicrosecond );
