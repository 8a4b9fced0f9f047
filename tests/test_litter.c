/* sere litter as a user meets it (issue #21): the scene depends on the seed alone, not on the
 * thread count nor on the MPI ranks; a rerun after a crash redoes only the missing leaves and gives the same scene;
 * one leaf's failure costs no other; a real glTF reader (assimp) opens litter.glb. Small leaves (400 points, 20 frames)
 * keep it to seconds; SERE_BIN names the binary under test. */
#define _DEFAULT_SOURCE
#include "fixture.h"

#include <assimp/cimport.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

/* Seed 6 draws wisteria, plane tree, maple and grass; 400 points are enough for every
 * species' outline and veins (the grass needs 390). */
#define LITTER_ARGS "--leaves 4 --seed 6 --points 400 --frames 20"

/* A fresh directory under /tmp; the caller removes it with sere_test_remove_tree. */
static void make_dir( char* dir, size_t size, const char* name )
{
	snprintf( dir, size, "/tmp/sere-litter-%s-XXXXXX", name );
	cr_assert_not_null( mkdtemp( dir ) );
}

/* The whole file, NUL terminated; *size its length. NULL when it cannot be read. */
static char* read_all( const char* path, long* size )
{
	FILE* f = fopen( path, "rb" );
	if ( f == NULL )
	{
		return NULL;
	}
	fseek( f, 0, SEEK_END );
	*size = ftell( f );
	fseek( f, 0, SEEK_SET );
	char* data = malloc( (size_t) *size + 1 );
	size_t got = data != NULL ? fread( data, 1, (size_t) *size, f ) : 0;
	fclose( f );
	if ( data != NULL )
	{
		data[got] = '\0';
	}
	return data;
}

/* The file name in the output directory dir, read whole (read_all); asserts it could be read. */
static char* read_output( const char* dir, const char* name )
{
	char path[256];
	snprintf( path, sizeof( path ), "%s/%s", dir, name );
	long size;
	char* data = read_all( path, &size );
	cr_assert_not_null( data, "cannot read %s", path );
	return data;
}

static void expect_same_file( const char* a, const char* b )
{
	long size_a = -1, size_b = -1;
	char* data_a = read_all( a, &size_a );
	char* data_b = read_all( b, &size_b );
	cr_assert_not_null( data_a, "cannot read %s", a );
	cr_assert_not_null( data_b, "cannot read %s", b );
	cr_expect( size_a > 0 && size_a == size_b && memcmp( data_a, data_b, (size_t) size_a ) == 0,
			   "%s (%ld bytes) and %s (%ld bytes) differ", a, size_a, b, size_b );
	free( data_a ), free( data_b );
}

static int litter( const char* dir, const char* extra, char* err, size_t err_size )
{
	char args[1024];
	snprintf( args, sizeof( args ), "litter " LITTER_ARGS " --out %s %s", dir, extra );
	return sere_test_run( args, err, err_size );
}

/* Two fresh directories (make_dir) holding the litter written on one thread in the first and
 * on two in the second. */
static void litter_one_and_two( char* first, char* second, size_t size, const char* first_name,
								const char* second_name )
{
	char err[4096];
	make_dir( first, size, first_name );
	make_dir( second, size, second_name );
	cr_assert_eq( litter( first, "--threads 1", err, sizeof( err ) ), 0, "%s", err );
	cr_assert_eq( litter( second, "--threads 2", err, sizeof( err ) ), 0, "%s", err );
}

static int count_of( const char* text, const char* phrase )
{
	int count = 0;
	for ( const char* at = strstr( text, phrase ); at != NULL; at = strstr( at + 1, phrase ) )
	{
		count += 1;
	}
	return count;
}

Test( litter, same_scene_on_one_and_two_threads )
{
	char one[64], two[64], a[128], b[128];
	litter_one_and_two( one, two, sizeof( one ), "t1", "t2" );
	snprintf( a, sizeof( a ), "%s/litter.ply", one );
	snprintf( b, sizeof( b ), "%s/litter.ply", two );
	expect_same_file( a, b );
	snprintf( a, sizeof( a ), "%s/litter.png", one );
	struct stat info;
	cr_expect( stat( a, &info ) == 0 && info.st_size > 0, "no %s", a );
	char* summary = read_output( one, "summary.json" );
	cr_expect_eq( count_of( summary, "\"status\": \"dried\"" ), 4, "%s", summary );
	cr_expect_not_null( strstr( summary, "\"failed\": 0" ), "%s", summary );
	free( summary );
	cr_expect_eq( sere_test_remove_tree( one ), 0 );
	cr_expect_eq( sere_test_remove_tree( two ), 0 );
}

Test( litter, rerun_redoes_missing_and_cut_leaves_only )
{
	char whole[64], resumed[64], err[4096], path[160], other[160];
	litter_one_and_two( whole, resumed, sizeof( whole ), "whole", "resumed" );
	/* a crash: one leaf never written, another cut short */
	snprintf( path, sizeof( path ), "%s/leaves/leaf_00001.ply", resumed );
	cr_assert_eq( unlink( path ), 0 );
	snprintf( path, sizeof( path ), "%s/leaves/leaf_00002.ply", resumed );
	struct stat info;
	cr_assert_eq( stat( path, &info ), 0 );
	cr_assert_eq( truncate( path, info.st_size / 2 ), 0 );
	snprintf( path, sizeof( path ), "%s/litter.ply", resumed );
	cr_assert_eq( unlink( path ), 0 );
	cr_assert_eq( litter( resumed, "--threads 2", err, sizeof( err ) ), 0, "%s", err );
	snprintf( path, sizeof( path ), "%s/litter.ply", whole );
	snprintf( other, sizeof( other ), "%s/litter.ply", resumed );
	expect_same_file( path, other );
	/* the two damaged leaves dried again, the others kept */
	char* summary = read_output( resumed, "summary.json" );
	cr_expect_eq( count_of( summary, "\"status\": \"dried\"" ), 2, "%s", summary );
	cr_expect_eq( count_of( summary, "\"status\": \"resumed\"" ), 2, "%s", summary );
	free( summary );
	/* a leaf written with other options is not reused */
	char changed[64];
	make_dir( changed, sizeof( changed ), "changed" );
	cr_assert_eq( litter( changed, "--threads 1", err, sizeof( err ) ), 0, "%s", err );
	cr_assert_eq( litter( changed, "--threads 1 --frames 10", err, sizeof( err ) ), 0, "%s", err );
	summary = read_output( changed, "summary.json" );
	cr_expect_eq( count_of( summary, "\"status\": \"dried\"" ), 4, "%s", summary );
	free( summary );
	cr_expect_eq( sere_test_remove_tree( whole ), 0 );
	cr_expect_eq( sere_test_remove_tree( resumed ), 0 );
	cr_expect_eq( sere_test_remove_tree( changed ), 0 );
}

Test( litter, failed_leaf_is_reported_and_costs_no_other )
{
	char dir[64], err[4096], path[160];
	make_dir( dir, sizeof( dir ), "fail" );
	/* a directory where leaf 1's file goes: that leaf cannot be written */
	snprintf( path, sizeof( path ), "%s/leaves", dir );
	cr_assert_eq( mkdir( path, 0755 ), 0 );
	snprintf( path, sizeof( path ), "%s/leaves/leaf_00001.ply", dir );
	cr_assert_eq( mkdir( path, 0755 ), 0 );
	int code = litter( dir, "--threads 2", err, sizeof( err ) );
	cr_expect_eq( code, 1, "exit %d: %s", code, err );
	cr_expect_not_null( strstr( err, "sere litter: leaf 1 (" ), "%s", err );
	cr_expect_not_null( strstr( err, "leaf_00001.ply is a directory, not a file" ), "%s", err );
	cr_expect_eq( count_of( err, "\n" ), 1, "one line per failed leaf: %s", err );
	for ( int i = 0; i < 4; ++i )
	{
		snprintf( path, sizeof( path ), "%s/leaves/leaf_%05d.ply", dir, i );
		struct stat info;
		cr_expect( stat( path, &info ) == 0 && ( i == 1 ) == S_ISDIR( info.st_mode ), "%s", path );
	}
	char* summary = read_output( dir, "summary.json" );
	cr_expect_eq( count_of( summary, "\"status\": \"dried\"" ), 3, "%s", summary );
	cr_expect_not_null( strstr( summary, "\"index\": 1," ), "%s", summary );
	cr_expect_not_null( strstr( summary, "is a directory, not a file\"" ), "%s", summary );
	cr_expect_not_null( strstr( summary, "\"failed\": 1" ), "%s", summary );
	free( summary );
	snprintf( path, sizeof( path ), "%s/litter.ply", dir );
	struct stat info;
	cr_expect( stat( path, &info ) == 0 && info.st_size > 0, "no %s", path );
	cr_expect_eq( sere_test_remove_tree( dir ), 0 );
}

/* Without --frames a leaf dries to the end, as sere run --until-dry does: the plane tree's
 * first layer runs dry within 400 frames (seconds at 400 points), far under the cap. An explicit
 * --frames stops it wet, and says nothing of it on stderr: the user chose it. */
Test( litter, dries_to_the_end_unless_frames_says_otherwise )
{
	char dir[64], err[4096];
	make_dir( dir, sizeof( dir ), "dry" );
	char args[512];
	cr_assert_eq( sere_test_run_in( "litter --leaves 1 --seed 6 --points 400 --preset plane-tree --out %s", dir, err,
									sizeof( err ) ),
				  0, "%s", err );
	cr_expect_eq( err[0], '\0', "nothing on stderr: %s", err );
	char* summary = read_output( dir, "summary.json" );
	const char* at = strstr( summary, "\"frames\": " );
	long frames = -1;
	cr_assert( at != NULL && sscanf( at, "\"frames\": %ld", &frames ) == 1, "%s", summary );
	cr_expect( frames > 30 && frames < 10000, "dried at frame %ld", frames );
	cr_expect_not_null( strstr( at, "\"desiccated\": true" ), "%s", summary );
	cr_expect_not_null( strstr( summary, "\"frames_max\": 10000" ), "%s", summary );
	cr_expect_not_null( strstr( summary, "\"desiccated\": 1" ), "%s", summary );
	free( summary );
	cr_expect_eq( sere_test_remove_tree( dir ), 0 );

	make_dir( dir, sizeof( dir ), "wet" );
	snprintf( args, sizeof( args ), "litter --leaves 1 --seed 6 --points 400 --preset plane-tree --frames 30 --out %s",
			  dir );
	cr_assert_eq( sere_test_run( args, err, sizeof( err ) ), 0, "%s", err );
	cr_expect_eq( err[0], '\0', "nothing on stderr: %s", err );
	summary = read_output( dir, "summary.json" );
	cr_expect_not_null( strstr( summary, "\"frames\": 30, \"desiccated\": false" ), "%s", summary );
	cr_expect_not_null( strstr( summary, "\"desiccated\": 0" ), "%s", summary );
	free( summary );
	cr_expect_eq( sere_test_remove_tree( dir ), 0 );
}

/* --preset makes every leaf one species and leaves the other draws alone: a later run without
 * it reuses exactly the leaf that was drawn that species (seed 6's leaf 1 is a plane tree) and
 * dries the others again, whose files hold another species. */
Test( litter, preset_sets_every_leaf_and_is_part_of_the_leaf_file )
{
	char dir[64], err[4096];
	make_dir( dir, sizeof( dir ), "preset" );
	cr_assert_eq( litter( dir, "--threads 2 --preset plane-tree", err, sizeof( err ) ), 0, "%s", err );
	char* summary = read_output( dir, "summary.json" );
	cr_expect_eq( count_of( summary, "\"preset\": \"plane-tree\"" ), 4, "%s", summary );
	free( summary );
	cr_assert_eq( litter( dir, "--threads 2", err, sizeof( err ) ), 0, "%s", err );
	summary = read_output( dir, "summary.json" );
	cr_expect_eq( count_of( summary, "\"preset\": \"plane-tree\"" ), 1, "%s", summary );
	cr_expect_not_null( strstr( summary, "\"index\": 1, \"species\": \"plane\"" ), "%s", summary );
	cr_expect_eq( count_of( summary, "\"status\": \"resumed\"" ), 1, "%s", summary );
	cr_expect_eq( count_of( summary, "\"status\": \"dried\"" ), 3, "%s", summary );
	free( summary );
	cr_expect_eq( sere_test_remove_tree( dir ), 0 );
}

/* Each leaf is its own simulation: two leaves of one preset sample their interior points with
 * different seeds, so their meshes (the face lists, the tail of each binary PLY, which placement
 * does not touch) differ. */
Test( litter, leaves_of_one_preset_are_different_meshes )
{
	char dir[64], err[4096], a[160], b[160];
	make_dir( dir, sizeof( dir ), "unique" );
	cr_assert_eq( litter( dir, "--threads 2 --preset maple-red", err, sizeof( err ) ), 0, "%s", err );
	snprintf( a, sizeof( a ), "%s/leaves/leaf_00000.ply", dir );
	snprintf( b, sizeof( b ), "%s/leaves/leaf_00001.ply", dir );
	long size_a = -1, size_b = -1;
	char* data_a = read_all( a, &size_a );
	char* data_b = read_all( b, &size_b );
	cr_assert( data_a != NULL && data_b != NULL );
	/* 13 bytes a triangle (a count byte and three int32): the last 100 triangles */
	const long tail = 1300;
	cr_assert( size_a > tail && size_b > tail );
	cr_expect_neq( memcmp( data_a + size_a - tail, data_b + size_b - tail, (size_t) tail ), 0,
				   "two maple-red leaves have the same triangles: one simulation repeated" );
	free( data_a ), free( data_b );
	cr_expect_eq( sere_test_remove_tree( dir ), 0 );
}

/* --progress 0: a line after every leaf but the last (whose end the summary line reports),
 * counting up, with an estimate of the time left. */
Test( litter, progress_lines_on_stderr )
{
	char dir[64], err[4096];
	make_dir( dir, sizeof( dir ), "progress" );
	cr_assert_eq( litter( dir, "--threads 1 --progress 0", err, sizeof( err ) ), 0, "%s", err );
	cr_expect_eq( count_of( err, "\n" ), 3, "%s", err );
	for ( int done = 1; done <= 3; ++done )
	{
		char line[64];
		snprintf( line, sizeof( line ), "sere litter: %d of 4 leaves done, ", done );
		cr_expect_not_null( strstr( err, line ), "no '%s' in: %s", line, err );
	}
	cr_expect_eq( count_of( err, " min left\n" ), 3, "%s", err );
	cr_expect_eq( sere_test_remove_tree( dir ), 0 );
}

static void expect_error( const char* args, const char* phrase )
{
	int code = sere_test_expect_error( args, phrase );
	cr_expect_eq( code, 2, "'%s' should fail with 2, not %d", args, code );
}

Test( litter, bad_options_one_clear_line )
{
	expect_error( "litter --seed 3 --out /tmp/sere-litter-bad", "missing --leaves N" );
	expect_error( "litter --leaves 0 --out /tmp/sere-litter-bad", "--leaves takes" );
	expect_error( "litter --leaves 2 --seed -1 --out /tmp/sere-litter-bad", "--seed takes" );
	expect_error( "litter --leaves 2 --points", "--points needs a value" );
	expect_error( "litter --leaves 2 --colour red", "unknown option '--colour'" );
	expect_error( "litter --leaves 2 maple", "unexpected argument 'maple'" );
	expect_error( "litter --leaves 2 --preset oak", "--preset takes one of 'maple-red', 'maple-green'" );
	expect_error( "litter --leaves 2 --progress -1", "--progress takes" );
}

Test( litter, glb_opens_in_assimp_with_the_ply_counts )
{
	char dir[64], err[4096], path[160];
	make_dir( dir, sizeof( dir ), "glb" );
	cr_assert_eq( litter( dir, "--threads 2", err, sizeof( err ) ), 0, "%s", err );
	/* the counts and the first vertex of litter.ply, the scene the .glb must hold */
	char* ply = read_output( dir, "litter.ply" );
	int vertices = 0, triangles = 0;
	const char* at = strstr( ply, "element vertex " );
	cr_assert( at != NULL && sscanf( at, "element vertex %d", &vertices ) == 1 );
	at = strstr( ply, "element face " );
	cr_assert( at != NULL && sscanf( at, "element face %d", &triangles ) == 1 );
	const char* body = strstr( ply, "end_header\n" );
	cr_assert_not_null( body );
	float first[3];
	memcpy( first, body + strlen( "end_header\n" ), sizeof( first ) );
	free( ply );
	cr_assert( vertices > 0 && triangles > 0 );

	snprintf( path, sizeof( path ), "%s/litter.glb", dir );
	const struct aiScene* scene = aiImportFile( path, aiProcess_ValidateDataStructure );
	cr_assert_not_null( scene, "assimp cannot open %s: %s", path, aiGetErrorString() );
	cr_assert_eq( scene->mNumMeshes, 1 );
	const struct aiMesh* mesh = scene->mMeshes[0];
	cr_expect_eq( (int) mesh->mNumVertices, vertices );
	cr_expect_eq( (int) mesh->mNumFaces, triangles );
	cr_expect_not_null( mesh->mNormals );
	cr_expect_not_null( mesh->mColors[0], "no COLOR_0" );
	int bad_faces = 0;
	for ( unsigned f = 0; f < mesh->mNumFaces; ++f )
	{
		bad_faces += mesh->mFaces[f].mNumIndices != 3;
	}
	cr_expect_eq( bad_faces, 0 );
	cr_expect( mesh->mVertices[0].x == first[0] && mesh->mVertices[0].y == first[1] && mesh->mVertices[0].z == first[2],
			   "first vertex (%g, %g, %g), the PLY's (%g, %g, %g)", (double) mesh->mVertices[0].x,
			   (double) mesh->mVertices[0].y, (double) mesh->mVertices[0].z, (double) first[0], (double) first[1],
			   (double) first[2] );
	if ( mesh->mNormals != NULL )
	{
		const struct aiVector3D n = mesh->mNormals[0];
		cr_expect_float_eq( sqrt( (double) n.x * n.x + (double) n.y * n.y + (double) n.z * n.z ), 1.0, 1e-5 );
	}
	aiReleaseImport( scene );
	cr_expect_eq( sere_test_remove_tree( dir ), 0 );
}

/* The ranks share the leaves but each leaf is still drawn from the seed and its index alone, and
 * rank 0 assembles the scene from the files in index order: one, two and three ranks (three
 * dealt 2, 2 and 1 of 5 leaves) and a run without mpirun give the same bytes. */
Test( litter, same_scene_on_one_two_and_three_ranks )
{
	char err[4096], command[1024];
	cr_assert_eq( sere_test_stdout( "litter --help", err, sizeof( err ) ), 0, "%s", err );
	if ( strstr( err, "Built with MPI" ) == NULL )
	{
		cr_skip( "%s was built without MPI (no Open MPI development files)", sere_test_bin() );
	}
	if ( system( "command -v mpirun >/dev/null 2>&1" ) != 0 )
	{
		cr_skip( "no mpirun on the PATH" );
	}
	char plain[64], path[160], other[160];
	make_dir( plain, sizeof( plain ), "plain" );
	snprintf( command, sizeof( command ), "litter --leaves 5 --seed 6 --points 400 --frames 20 --out %s", plain );
	cr_assert_eq( sere_test_run( command, err, sizeof( err ) ), 0, "%s", err );
	snprintf( path, sizeof( path ), "%s/litter.ply", plain );
	for ( int ranks = 1; ranks <= 3; ++ranks )
	{
		char dir[64];
		make_dir( dir, sizeof( dir ), "mpi" );
		snprintf( command, sizeof( command ),
				  "mpirun --allow-run-as-root --oversubscribe -np %d %s litter --leaves 5 --seed 6 --points 400 "
				  "--frames 20 --threads 1 --out %s 2>&1 >/dev/null",
				  ranks, sere_test_bin(), dir );
		cr_assert_eq( sere_test_shell( command, err, sizeof( err ) ), 0, "%d ranks: %s", ranks, err );
		snprintf( other, sizeof( other ), "%s/litter.ply", dir );
		expect_same_file( path, other );
		/* every rank dried its share: the summary names each rank */
		char* summary = read_output( dir, "summary.json" );
		for ( int r = 0; r < ranks; ++r )
		{
			char rank[32];
			snprintf( rank, sizeof( rank ), "\"rank\": %d, \"status\"", r );
			cr_expect_not_null( strstr( summary, rank ), "%d ranks, no leaf on rank %d: %s", ranks, r, summary );
		}
		cr_expect_eq( count_of( summary, "\"status\": \"dried\"" ), 5, "%s", summary );
		free( summary );
		cr_expect_eq( sere_test_remove_tree( dir ), 0 );
	}
	cr_expect_eq( sere_test_remove_tree( plain ), 0 );
}
