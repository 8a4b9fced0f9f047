/* sere fuzz — the season readers: the Markov chain file and the weather schedule
 * (harness/cli/cmd_season_files.c, season_read_chain and season_read_schedule, declared in
 * cmd_season_shared.h) and the key points file (harness/read/seasonleaf.c, read_keys, through
 * seasonleaf_shim.c).
 *
 * Every input is given to all three readers, so the seeds of each format (chains,
 * schedules, key points) teach the fuzzer all of them. What a reader accepts is used the way
 * `sere season` uses it: a chain gives transition matrices (rows summing to 1) and sampling
 * tables over the whole weather range, a schedule gives the weather of every day. */
#define _GNU_SOURCE
#include "fuzz.h"

#include "cli/cmd_season_shared.h"
#include "seasonleaf_shim.h"

#include <math.h>

int LLVMFuzzerInitialize( int* argc, char*** argv )
{
	(void) argc, (void) argv;
	fuzz_quiet();
	return 0;
}

static chain_file fuzz_chain;
static schedule fuzz_plan;
static double fuzz_P[MAX_STATES * MAX_STATES];
static sere_markov_day fuzz_day;

static void use_chain( const chain_file* c )
{
	FUZZ_CHECK( c->state_count >= 1 && c->state_count <= MAX_STATES );
	FUZZ_CHECK( c->initial >= 0 && c->initial < c->state_count );
	const double temperature[3] = { -90.0, 0.5 * ( c->chain.cold + c->chain.warm ), 70.0 };
	const double humidity[3] = { 0.0, 0.5 * ( c->chain.dry + c->chain.wet ), 1.0 };
	const int32_t S = c->state_count;
	for ( int k = 0; k < 3; ++k )
	{
		FUZZ_CHECK( sere_markov_matrix( &c->chain, temperature[k], humidity[k], fuzz_P ) == SERE_OK );
		for ( int32_t i = 0; i < S; ++i )
		{
			double sum = 0.0;
			for ( int32_t j = 0; j < S; ++j )
			{
				FUZZ_CHECK( fuzz_P[i * S + j] >= 0.0 && fuzz_P[i * S + j] <= 1.0 );
				sum += fuzz_P[i * S + j];
			}
			FUZZ_CHECK( fabs( sum - 1.0 ) < 1e-9 );
		}
		FUZZ_CHECK( sere_markov_day_prepare( &c->chain, temperature[k], humidity[k], &fuzz_day ) == SERE_OK );
	}
}

static void use_schedule( const schedule* s )
{
	FUZZ_CHECK( s->count >= 2 && s->count <= MAX_SCHEDULE && s->day[0] == 0 );
	const int32_t last = s->day[s->count - 1];
	const int32_t step = last / 64 > 0 ? last / 64 : 1;
	for ( int32_t day = 0; day <= last + 1; day += step )
	{
		double t, h;
		season_weather( s, day, &t, &h );
		FUZZ_CHECK( t >= -90.0 && t <= 70.0 && h >= 0.0 && h <= 1.0 );
	}
}

int LLVMFuzzerTestOneInput( const uint8_t* data, size_t size )
{
	const char* path = fuzz_file( data, size );
	if ( season_read_chain( path, &fuzz_chain ) == 0 )
	{
		use_chain( &fuzz_chain );
	}
	if ( season_read_schedule( path, &fuzz_plan ) == 0 )
	{
		use_schedule( &fuzz_plan );
	}
	double* xy = NULL;
	int32_t count = 0, width = 0, height = 0;
	char err[1024] = "";
	if ( fuzz_read_keys( path, &xy, &count, &width, &height, err, sizeof( err ) ) == SERE_OK )
	{
		FUZZ_CHECK( count >= 3 && width >= 2 && height >= 2 );
		for ( int32_t i = 0; i < count; ++i )
		{
			FUZZ_CHECK( xy[2 * i] >= 0.0 && xy[2 * i] <= width && xy[2 * i + 1] >= 0.0 && xy[2 * i + 1] <= height );
		}
		free( xy );
	}
	else
	{
		FUZZ_CHECK( err[0] != '\0' && xy == NULL );
	}
	return 0;
}
