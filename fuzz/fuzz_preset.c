/* sere fuzz — preset files and --set key=value (harness/common/params.c).
 *
 * Every input is read three ways: as a preset file (sere_params_load_preset), whole as one
 * --set argument (sere_params_set), and line by line as a list of --set arguments
 * (sere_params_apply). A failure must come with a message; what was accepted is printed the way
 * the summaries print it. */
#define _GNU_SOURCE
#include "fuzz.h"

#include "common/params.h"

#include <string.h>

static FILE* sink;

int LLVMFuzzerInitialize( int* argc, char*** argv )
{
	(void) argc, (void) argv;
	fuzz_quiet();
	sink = fopen( "/dev/null", "w" );
	if ( sink == NULL )
	{
		abort();
	}
	return 0;
}

#define MAX_SETS 64

int LLVMFuzzerTestOneInput( const uint8_t* data, size_t size )
{
	char err[1024] = "";
	sere_sim_params params = sere_sim_params_default();
	if ( sere_params_load_preset( &params, fuzz_file( data, size ), err, sizeof( err ) ) != 0 )
	{
		FUZZ_CHECK( err[0] != '\0' );
	}
	else
	{
		FUZZ_CHECK( params.layer.m_max >= params.layer.m_min );
		sere_params_print_json( &params, sink, "  " );
	}

	char* text = fuzz_string( data, size );
	params = sere_sim_params_default();
	err[0] = '\0';
	if ( sere_params_set( &params, text, err, sizeof( err ) ) != 0 )
	{
		FUZZ_CHECK( err[0] != '\0' );
	}

	const char* sets[MAX_SETS];
	int count = 0;
	for ( char *save = NULL, *line = strtok_r( text, "\n", &save ); line != NULL && count < MAX_SETS;
		  line = strtok_r( NULL, "\n", &save ) )
	{
		sets[count++] = line;
	}
	params = sere_sim_params_default();
	err[0] = '\0';
	if ( sere_params_apply( &params, NULL, sets, count, err, sizeof( err ) ) != 0 )
	{
		FUZZ_CHECK( err[0] != '\0' );
	}
	else
	{
		sere_params_print_json( &params, sink, "  " );
	}
	free( text );
	return 0;
}
