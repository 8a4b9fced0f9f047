/* Our meshes opened with the readers users open them in: VTK's own vtkPLYReader and
 * vtkXMLPolyDataReader (the code ParaView runs) from Debian's python3-vtk9, through
 * tests/read_mesh.py, which prints what they read as one line. A file VTK cannot read, or reads
 * with a different count, array or geometry than sere says it wrote, fails here with the
 * reader's words. SERE_BIN names the binary under test; SERE_PYTHON the interpreter, by default
 * /usr/bin/python3, the one python3-vtk9 installs for (a python3 first on PATH, such as pyenv's
 * or a virtual environment's, does not see it). */
#define _DEFAULT_SOURCE
#include "fixture.h"

#include <criterion/criterion.h>
#include <dirent.h>
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- what the readers say ------------------------------------------------------------------- */

/* A point-data array as tests/read_mesh.py summarizes it. */
typedef struct read_array
{
	char name[64];
	int tuples, components, nonfinite;
	double min, max;
	int fractional; /* finite values that are not whole numbers */
} read_array;

/* A .ply or .vtp as VTK read it. */
typedef struct read_mesh
{
	int points, polys, triangles;
	char digest[16]; /* CRC-32 of the points and triangle corners: equal for a PLY and a VTP of one mesh */
	int array_count;
	read_array arrays[8];
} read_mesh;

/* Runs tests/read_mesh.py on path with stdout and stderr in out (a Python traceback included);
 * returns the exit status, 128 when it did not exit. */
static int run_reader( const char* path, char* out, size_t out_size )
{
	const char* python = getenv( "SERE_PYTHON" );
	char command[4200];
	snprintf( command, sizeof( command ), "%s tests/read_mesh.py '%s' 2>&1",
			  python != NULL ? python : "/usr/bin/python3", path );
	return sere_test_shell( command, out, out_size );
}

/* The reader's line for path, which must start with kind ("mesh" or "pvd"); anything else fails
 * the test with all the reader printed. */
static void reader_line( const char* path, const char* kind, char* line, size_t line_size )
{
	int status = run_reader( path, line, line_size );
	size_t length = strlen( kind );
	cr_assert( status == 0 && strncmp( line, kind, length ) == 0 && line[length] == ' ',
			   "%s: VTK did not read it (tests/read_mesh.py, exit status %d): %s", path, status, line );
	line[strcspn( line, "\n" )] = '\0';
}

static void read_with_vtk( const char* path, read_mesh* mesh )
{
	char line[8192];
	reader_line( path, "mesh", line, sizeof( line ) );
	memset( mesh, 0, sizeof( *mesh ) );
	char* rest;
	char* token = strtok_r( line + strlen( "mesh " ), " ", &rest );
	cr_assert( token != NULL && sscanf( token, "%d", &mesh->points ) == 1, "%s: bad reader line", path );
	token = strtok_r( NULL, " ", &rest );
	cr_assert( token != NULL && sscanf( token, "%d", &mesh->polys ) == 1, "%s: bad reader line", path );
	token = strtok_r( NULL, " ", &rest );
	cr_assert( token != NULL && sscanf( token, "%d", &mesh->triangles ) == 1, "%s: bad reader line", path );
	token = strtok_r( NULL, " ", &rest );
	cr_assert( token != NULL && sscanf( token, "%15s", mesh->digest ) == 1, "%s: bad reader line", path );
	while ( ( token = strtok_r( NULL, " ", &rest ) ) != NULL )
	{
		cr_assert_lt( mesh->array_count, 8, "%s: more arrays than the test expects", path );
		read_array* a = mesh->arrays + mesh->array_count++;
		cr_assert_eq( sscanf( token, "%63[^=]=%d,%d,%d,%lf,%lf,%d", a->name, &a->tuples, &a->components, &a->nonfinite,
							  &a->min, &a->max, &a->fractional ),
					  7, "%s: bad array in the reader line: %s", path, token );
	}
}

static const read_array* find_array( const read_mesh* mesh, const char* name )
{
	for ( int k = 0; k < mesh->array_count; ++k )
	{
		if ( strcmp( mesh->arrays[k].name, name ) == 0 )
		{
			return mesh->arrays + k;
		}
	}
	return NULL;
}

/* ---- what the files say --------------------------------------------------------------------- */

/* A PLY header: the counts and each element's property lines without "property " ("float x"). */
typedef struct ply_header
{
	bool binary_little_endian;
	int vertices, faces;
	int vertex_property_count, face_property_count;
	char vertex_properties[16][256];
	char face_properties[4][256];
} ply_header;

static void read_ply_header( const char* path, ply_header* header )
{
	memset( header, 0, sizeof( *header ) );
	FILE* f = fopen( path, "rb" );
	cr_assert_not_null( f, "cannot open %s", path );
	char line[256];
	char element[16] = "";
	bool ended = false;
	while ( !ended && fgets( line, sizeof( line ), f ) != NULL )
	{
		line[strcspn( line, "\n" )] = '\0';
		int count;
		char name[16];
		if ( strcmp( line, "format binary_little_endian 1.0" ) == 0 )
		{
			header->binary_little_endian = true;
		}
		else if ( sscanf( line, "element %15s %d", name, &count ) == 2 )
		{
			snprintf( element, sizeof( element ), "%s", name );
			header->vertices = strcmp( name, "vertex" ) == 0 ? count : header->vertices;
			header->faces = strcmp( name, "face" ) == 0 ? count : header->faces;
		}
		else if ( strncmp( line, "property ", 9 ) == 0 && strcmp( element, "vertex" ) == 0 )
		{
			cr_assert_lt( header->vertex_property_count, 16, "%s: too many vertex properties", path );
			snprintf( header->vertex_properties[header->vertex_property_count++], 256, "%s", line + 9 );
		}
		else if ( strncmp( line, "property ", 9 ) == 0 && strcmp( element, "face" ) == 0 )
		{
			cr_assert_lt( header->face_property_count, 4, "%s: too many face properties", path );
			snprintf( header->face_properties[header->face_property_count++], 256, "%s", line + 9 );
		}
		ended = strcmp( line, "end_header" ) == 0;
	}
	fclose( f );
	cr_assert( ended, "%s: no end_header", path );
}

/* The whole-number member key of a JSON object sere printed. */
static int json_int( const char* json, const char* key )
{
	char quoted[128];
	snprintf( quoted, sizeof( quoted ), "\"%s\": ", key );
	const char* at = strstr( json, quoted );
	cr_assert_not_null( at, "no %s in %s", key, json );
	return atoi( at + strlen( quoted ) );
}

static void read_file( const char* path, char* text, size_t size )
{
	FILE* f = fopen( path, "rb" );
	cr_assert_not_null( f, "cannot open %s", path );
	size_t used = fread( text, 1, size - 1, f );
	text[used] = '\0';
	fclose( f );
}

static int compare_names( const void* a, const void* b )
{
	return strcmp( *(const char* const*) a, *(const char* const*) b );
}

/* ---- the checks ----------------------------------------------------------------------------- */

/* A per-vertex property a command writes and the values it may take. */
typedef struct expected_array
{
	const char* name;
	double lo, hi;
	bool whole; /* only whole numbers (a flag) */
} expected_array;

/* The .ply and .vtp of one frame (the same path but for the extension, given without it) hold
 * points and triangles, as the PLY header says; VTK reads both with those counts and the same
 * geometry, and the VTP's point data is the header's properties after x, y, z, in order, each
 * one value per point within its range. */
static void check_frame( const char* base, int points, int triangles, const expected_array* arrays, int array_count )
{
	char ply_path[4300], vtp_path[4300];
	snprintf( ply_path, sizeof( ply_path ), "%s.ply", base );
	snprintf( vtp_path, sizeof( vtp_path ), "%s.vtp", base );
	ply_header header;
	read_ply_header( ply_path, &header );
	cr_expect( header.binary_little_endian, "%s: not binary little endian", ply_path );
	cr_expect_eq( header.vertices, points, "%s: header has %d vertices, sere made %d", ply_path, header.vertices,
				  points );
	cr_expect_eq( header.faces, triangles, "%s: header has %d faces, sere made %d", ply_path, header.faces, triangles );
	cr_expect_eq( header.vertex_property_count, 3 + array_count, "%s: %d vertex properties, expected %d", ply_path,
				  header.vertex_property_count, 3 + array_count );
	const char* xyz[3] = { "x", "y", "z" };
	for ( int k = 0; k < 3 + array_count && k < header.vertex_property_count; ++k )
	{
		char expected[64];
		snprintf( expected, sizeof( expected ), "float %s", k < 3 ? xyz[k] : arrays[k - 3].name );
		cr_expect_str_eq( header.vertex_properties[k], expected, "%s: vertex property %d is '%s', expected '%s'",
						  ply_path, k, header.vertex_properties[k], expected );
	}
	cr_expect( header.face_property_count == 1 &&
				   strcmp( header.face_properties[0], "list uchar int vertex_indices" ) == 0,
			   "%s: faces are not one 'list uchar int vertex_indices'", ply_path );

	read_mesh ply, vtp;
	read_with_vtk( ply_path, &ply );
	read_with_vtk( vtp_path, &vtp );
	const read_mesh* meshes[2] = { &ply, &vtp };
	const char* paths[2] = { ply_path, vtp_path };
	for ( int m = 0; m < 2; ++m )
	{
		cr_expect_eq( meshes[m]->points, header.vertices, "%s: VTK read %d points, the header says %d", paths[m],
					  meshes[m]->points, header.vertices );
		cr_expect_eq( meshes[m]->polys, header.faces, "%s: VTK read %d polygons, the header says %d", paths[m],
					  meshes[m]->polys, header.faces );
		cr_expect_eq( meshes[m]->triangles, meshes[m]->polys, "%s: %d of %d polygons are triangles", paths[m],
					  meshes[m]->triangles, meshes[m]->polys );
	}
	/* vtkPLYReader (VTK 9.1) skips properties it has no use for but steps over each by its
	 * declared size, so a header that disagrees with the body moves every point after the
	 * first and every face. */
	cr_expect_str_eq( ply.digest, vtp.digest, "%s and %s: VTK read different points or triangles", ply_path, vtp_path );
	cr_expect_eq( vtp.array_count, array_count, "%s: VTK read %d point arrays, expected %d", vtp_path, vtp.array_count,
				  array_count );
	for ( int k = 0; k < array_count; ++k )
	{
		const expected_array* e = arrays + k;
		const read_array* a = find_array( &vtp, e->name );
		cr_expect_not_null( a, "%s: no point array '%s'", vtp_path, e->name );
		if ( a == NULL )
		{
			continue;
		}
		cr_expect( a == vtp.arrays + k, "%s: '%s' is not point array %d as in the PLY header", vtp_path, e->name, k );
		cr_expect( a->tuples == points && a->components == 1, "%s: '%s' has %d x %d values for %d points", vtp_path,
				   e->name, a->tuples, a->components, points );
		cr_expect_eq( a->nonfinite, 0, "%s: '%s' has %d values that are not finite", vtp_path, e->name, a->nonfinite );
		cr_expect( a->min >= e->lo && a->max <= e->hi, "%s: '%s' spans [%g, %g], outside [%g, %g]", vtp_path, e->name,
				   a->min, a->max, e->lo, e->hi );
		cr_expect( !e->whole || a->fractional == 0, "%s: '%s' has %d values that are not whole", vtp_path, e->name,
				   a->fractional );
	}
}

/* A command's mesh series: the .pvd at pvd_path lists, at increasing times, exactly the .vtp
 * files in frames_dir (listed as prefix + name), frame_count of them, each of which VTK opens
 * through the list with the frame's counts; each listed frame then passes check_frame. */
static void check_series( const char* pvd_path, const char* frames_dir, const char* prefix, int frame_count, int points,
						  int triangles, const expected_array* arrays, int array_count )
{
	DIR* dir = opendir( frames_dir );
	cr_assert_not_null( dir, "cannot list %s", frames_dir );
	char* written[64];
	int written_count = 0;
	struct dirent* entry;
	while ( ( entry = readdir( dir ) ) != NULL )
	{
		size_t length = strlen( entry->d_name );
		if ( length > 4 && strcmp( entry->d_name + length - 4, ".vtp" ) == 0 )
		{
			cr_assert_lt( written_count, 64, "%s: more frames than the test expects", frames_dir );
			written[written_count++] = strdup( entry->d_name );
		}
	}
	closedir( dir );
	qsort( written, (size_t) written_count, sizeof( written[0] ), compare_names );
	cr_expect_eq( written_count, frame_count, "%s: %d frames written, expected %d", frames_dir, written_count,
				  frame_count );

	char line[16384];
	reader_line( pvd_path, "pvd", line, sizeof( line ) );
	char* rest;
	char* token = strtok_r( line + strlen( "pvd " ), " ", &rest );
	int listed = token != NULL ? atoi( token ) : -1;
	cr_expect_eq( listed, written_count, "%s lists %d datasets, %d frames were written", pvd_path, listed,
				  written_count );
	double previous = -INFINITY;
	for ( int k = 0; ( token = strtok_r( NULL, " ", &rest ) ) != NULL; ++k )
	{
		char name[256], expected[256];
		double time;
		int listed_points, listed_polys;
		cr_assert_eq( sscanf( token, "%255[^@]@%lf:%d:%d", name, &time, &listed_points, &listed_polys ), 4,
					  "%s: bad reader entry: %s", pvd_path, token );
		cr_assert_lt( k, written_count, "%s lists %s past the frames written", pvd_path, name );
		snprintf( expected, sizeof( expected ), "%s%s", prefix, written[k] );
		cr_expect_str_eq( name, expected, "%s: dataset %d is %s, expected %s", pvd_path, k, name, expected );
		cr_expect_gt( time, previous, "%s: %s at time %g, not after %g", pvd_path, name, time, previous );
		previous = time;
		cr_expect( listed_points == points && listed_polys == triangles,
				   "%s: VTK read %s through it with %d points and %d polygons, expected %d and %d", pvd_path, name,
				   listed_points, listed_polys, points, triangles );
	}
	for ( int k = 0; k < written_count; ++k )
	{
		char base[4200];
		snprintf( base, sizeof( base ), "%s/%.*s", frames_dir, (int) strlen( written[k] ) - 4, written[k] );
		check_frame( base, points, triangles, arrays, array_count );
		free( written[k] );
	}
}

/* ---- the commands --------------------------------------------------------------------------- */

Test( readers, run_frames_open_in_vtk )
{
	char* dir = sere_test_scratch( "readers-run" );
	char err[4096], text[65536];
	cr_assert_eq(
		sere_test_run_in( "run data/leaves/wisteria.leaf --points 300 --frames 3 --out %s", dir, err, sizeof( err ) ),
		0, "%s", err );
	/* the triangle layer's point count is the model's (summary.json counts both layers) */
	cr_assert_eq( sere_test_stdout( "model data/leaves/wisteria.leaf --points 300 --json", text, sizeof( text ) ), 0 );
	int points = json_int( text, "triangle_particles" ), particles = json_int( text, "particles" );
	char path[4200];
	snprintf( path, sizeof( path ), "%s/summary.json", dir );
	read_file( path, text, sizeof( text ) );
	cr_assert_eq( json_int( text, "particles" ), particles, "run built another model than sere model" );
	int triangles = json_int( text, "triangles" );
	const expected_array arrays[] = {
		{ "water", 0.0, INFINITY, false },
		{ "tau", 0.0, 1.0, false },
		{ "relative_water", 0.0, 1.0001, false },
		{ "vein", 0.0, 1.0, true },
	};
	char frames[4200];
	snprintf( path, sizeof( path ), "%s/leaf.pvd", dir );
	snprintf( frames, sizeof( frames ), "%s/frames", dir );
	/* frames 0 to 3: with fewer than 24 frames every one is written */
	check_series( path, frames, "frames/", 4, points, triangles, arrays, 4 );
	sere_test_scratch_remove( dir );
}

Test( readers, wilt_frames_open_in_vtk )
{
	char* dir = sere_test_scratch( "readers-wilt" );
	char args[1024], json[8192];
	snprintf( args, sizeof( args ), "wilt --frames 3 --format ply,vtp --json --out %s", dir );
	cr_assert_eq( sere_test_stdout( args, json, sizeof( json ) ), 0, "sere %s failed", args );
	int points = json_int( json, "vertices" ), triangles = json_int( json, "triangles" );
	const expected_array arrays[] = {
		{ "u", 0.0, 1.0, false },
		{ "v", 0.0, 1.0, false },
		{ "droop", -INFINITY, INFINITY, false },
		{ "wilt_t", 0.0, 1.0, false },
	};
	char path[4200];
	snprintf( path, sizeof( path ), "%s/wilt.pvd", dir );
	check_series( path, dir, "", 3, points, triangles, arrays, 4 );
	/* u and v are the names PLY readers take for texture coordinates: VTK reads them from the
	 * PLY itself, one pair per point in [0, 1] */
	read_mesh ply;
	snprintf( path, sizeof( path ), "%s/frame_0002.ply", dir );
	read_with_vtk( path, &ply );
	const read_array* uv = find_array( &ply, "TCoords" );
	cr_assert_not_null( uv, "%s: VTK read no texture coordinates from u, v", path );
	cr_expect( uv->tuples == points && uv->components == 2 && uv->nonfinite == 0 && uv->min >= 0.0 && uv->max <= 1.0,
			   "%s: texture coordinates %d x %d, %d not finite, in [%g, %g]", path, uv->tuples, uv->components,
			   uv->nonfinite, uv->min, uv->max );
	sere_test_scratch_remove( dir );
}
