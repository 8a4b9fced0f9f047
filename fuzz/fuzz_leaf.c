/* sere fuzz — the .leaf reader (harness/read/leaffile.c, data/leaves/FORMAT.md).
 *
 * Every input is read with sere_leaf_file_read. A rejected input must come back with one line in err
 * and nothing to free. An accepted one must be a valid shape, and must survive the round trip
 * leaffile.h promises: sere_leaf_file_write, then sere_leaf_file_read, returns it bit for bit. */
#define _GNU_SOURCE
#include "fuzz.h"

#include "read/leaffile.h"

#include <string.h>

static char round_trip[64], round_trip_dir[64];

static void remove_round_trip( void )
{
	unlink( round_trip );
	rmdir( round_trip_dir );
}

int LLVMFuzzerInitialize( int* argc, char*** argv )
{
	(void) argc, (void) argv;
	fuzz_quiet();
	char dir[] = "/tmp/sere-fuzz-leaf-XXXXXX";
	if ( mkdtemp( dir ) == NULL )
	{
		perror( "mkdtemp" );
		abort();
	}
	snprintf( round_trip_dir, sizeof( round_trip_dir ), "%s", dir );
	snprintf( round_trip, sizeof( round_trip ), "%s/again.leaf", dir );
	atexit( remove_round_trip );
	return 0;
}

static int same_doubles( const double* a, const double* b, int32_t count )
{
	return count == 0 || memcmp( a, b, sizeof( double ) * (size_t) count ) == 0;
}

int LLVMFuzzerTestOneInput( const uint8_t* data, size_t size )
{
	const char* path = fuzz_file( data, size );
	sere_leaf_file leaf;
	char err[1024] = "";
	sere_status status = sere_leaf_file_read( path, &leaf, err, sizeof( err ) );
	if ( status != SERE_OK )
	{
		FUZZ_CHECK( err[0] != '\0' && strchr( err, '\n' ) == NULL );
		FUZZ_CHECK( leaf.outline_xy == NULL && leaf.vein_xy == NULL && leaf.veins == NULL );
		return 0;
	}
	const sere_leaf_shape* shape = &leaf.shape;
	sere_shape_check check;
	FUZZ_CHECK( sere_shape_validate( shape, &check ) == SERE_OK );

	/* The name is written when the writer can keep it (it refuses control characters the reader
	 * lets through); the geometry always. */
	const char* name = leaf.name;
	status = sere_leaf_file_write( round_trip, shape, name, err, sizeof( err ) );
	if ( status == SERE_ERR_ARGUMENT && strstr( err, "the name must be" ) != NULL )
	{
		name = NULL;
		status = sere_leaf_file_write( round_trip, shape, NULL, err, sizeof( err ) );
	}
	FUZZ_CHECK( status == SERE_OK );
	sere_leaf_file again;
	status = sere_leaf_file_read( round_trip, &again, err, sizeof( err ) );
	FUZZ_CHECK( status == SERE_OK );
	const sere_leaf_shape* back = &again.shape;
	FUZZ_CHECK( name == NULL || strcmp( again.name, leaf.name ) == 0 );
	FUZZ_CHECK( back->base_x == shape->base_x && back->base_y == shape->base_y );
	FUZZ_CHECK( back->outline_count == shape->outline_count && back->vein_count == shape->vein_count &&
				back->vein_point_count == shape->vein_point_count );
	FUZZ_CHECK( same_doubles( back->outline_xy, shape->outline_xy, 2 * shape->outline_count ) );
	FUZZ_CHECK( same_doubles( back->vein_xy, shape->vein_xy, 2 * shape->vein_point_count ) );
	FUZZ_CHECK( shape->vein_count == 0 ||
				memcmp( back->veins, shape->veins, sizeof( sere_vein ) * (size_t) shape->vein_count ) == 0 );
	sere_leaf_file_destroy( &again );
	sere_leaf_file_destroy( &leaf );
	return 0;
}
