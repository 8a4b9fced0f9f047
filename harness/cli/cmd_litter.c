/* sere litter — N leaves drying on the ground as one autumn scene (issue #21). Every leaf is
 * drawn from (seed, index) alone and dried as `sere run` dries it, then written on its own, so a
 * rerun into the same directory redoes only the leaves that are missing, and one leaf's failure
 * costs no other leaf. */
#define _POSIX_C_SOURCE 200809L
#include "cli/cmd_leaf.h"
#include "cli/cmd_litter_shared.h"
#include "cli/commands.h"
#include "cli/options.h"
#include "common/io.h"
#include "common/params.h"
#include "common/topo.h"
#include "core/array.h"
#include "drying/leaf.h"
#include "read/build.h"
#include "render/glb.h"
#include "render/leafpics.h"
#include "render/render.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <omp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

/* The shipped leaves that have a preset, the species a litter draws from. */
static const char* const species_names[] = { "maple", "maple", "plane", "wisteria", "grass" };
/* NULL-terminated: the choices of --preset */
static const char* const preset_names[] = { "maple-red", "maple-green", "plane-tree", "wisteria", "grass", NULL };
enum
{
	species_count = sizeof( species_names ) / sizeof( species_names[0] )
};

/* What drying a leaf of each species costs, for sharing the leaves out by particles x frames
 * (issue #21): its ms per frame at 600 points on one thread, and the frames it takes to dry at
 * 600 points (sere run's until-dry rule: a layer ran dry, Sec. 6). Every leaf of a run has the
 * same points, and a leaf's scale, turn and place are applied after it dried, so the species
 * alone tells the leaves' costs apart: ms per frame times the dry frames, or the cap if sooner. */
/* mean over a whole dry at 600 points, 1 thread, quiet machine (load 1), sere run --until-dry */
static const double species_ms_per_frame[] = { 0.85, 1.05, 0.70, 1.19, 2.75 };
static const long species_dry_frames[] = { 5000, 1016, 366, 2457, 4534 };

/* Frames a leaf may take to dry unless --frames says otherwise: twice the slowest species'. */
#define LITTER_FRAME_CAP 10000

/* One leaf of the scene as its seed and index draw it. */
typedef struct litter_draw
{
	int species;
	double scale, angle, x, y;
	uint32_t sample_seed; /* the interior points' seed: each leaf its own mesh, so its own dried shape */
} litter_draw;

/* What the leaf files must say about the run that wrote them to be reused. */
typedef struct litter_options
{
	const char* out;
	long leaves, seed, points, frames;
	int species;	  /* every leaf of this species (--preset), or -1: drawn per leaf */
	int frames_given; /* --frames chose the cap: leaves it stops before they dry are no surprise */
	long progress;	  /* seconds between progress lines on stderr */
} litter_options;

/* A leaf's final triangle layer in the scene, or the whole scene. */
typedef struct litter_mesh
{
	float *x, *y, *z, *rwc;
	uint8_t* rgb;
	int32_t* tri;
	int32_t vertices, triangles;
} litter_mesh;

static void mesh_free( litter_mesh* m )
{
	free( m->x ), free( m->y ), free( m->z ), free( m->rwc ), free( m->rgb ), free( m->tri );
	*m = ( litter_mesh ){ 0 };
}

static int mesh_alloc( litter_mesh* m, int32_t vertices, int32_t triangles )
{
	size_t n = (size_t) vertices > 0 ? (size_t) vertices : 1, t = (size_t) triangles > 0 ? (size_t) triangles : 1;
	*m = ( litter_mesh ){ malloc( sizeof( float ) * n ),
						  malloc( sizeof( float ) * n ),
						  malloc( sizeof( float ) * n ),
						  malloc( sizeof( float ) * n ),
						  malloc( 3 * n ),
						  malloc( sizeof( int32_t ) * 3 * t ),
						  vertices,
						  triangles };
	if ( !m->x || !m->y || !m->z || !m->rwc || !m->rgb || !m->tri )
	{
		mesh_free( m );
		return -1;
	}
	return 0;
}

/* The leaves fall on a square that grows with their number, about two leaves' area (a leaf is
 * about one unit across) of room each, so a litter of any size is dense but mostly one layer:
 * leaves do not collide with each other. */
static litter_draw draw_leaf( const litter_options* o, long index )
{
	/* a leaf's numbers come from its own stream, so they do not depend on how many leaves there
	 * are, which were dried before it, or on which thread */
	uint64_t state = (uint64_t) o->seed;
	state = sere_splitmix64( &state ) ^ ( (uint64_t) index * 0xd1b54a32d192ed03ull );
	litter_draw d;
	d.species = (int) ( sere_splitmix_unit( &state ) * species_count );
	/* a chosen species takes the drawn one's place, the other draws unchanged */
	d.species = o->species >= 0 ? o->species : d.species;
	d.scale = 0.7 + 0.6 * sere_splitmix_unit( &state );
	d.angle = 2.0 * 3.14159265358979323846 * sere_splitmix_unit( &state );
	double side = 1.5 * sqrt( (double) o->leaves );
	d.x = side * ( sere_splitmix_unit( &state ) - 0.5 );
	d.y = side * ( sere_splitmix_unit( &state ) - 0.5 );
	d.sample_seed = (uint32_t) ( sere_splitmix64( &state ) >> 32 );
	return d;
}

/* Deals the leaves to the ranks, statically and the same on every rank: the costliest first,
 * each to the least loaded rank (ties to the lowest rank), so that the ranks finish together
 * without talking to each other. order[] gets the dealing order, owner[] each leaf's rank. */
static long leaf_cost( const litter_options* o, long index )
{
	int s = draw_leaf( o, index ).species;
	long frames = species_dry_frames[s] < o->frames ? species_dry_frames[s] : o->frames;
	return lrint( 1000.0 * species_ms_per_frame[s] * (double) frames );
}

static int share_leaves( const litter_options* o, int ranks, long* order, int* owner )
{
	long leaves = o->leaves;
	long* load = calloc( (size_t) ranks, sizeof( long ) );
	/* the costliest first (the complement turns the larger cost into the smaller key), ties by
	 * index: the order in which the leaves are dealt out */
	sere_sort_item* costs = malloc( sizeof( sere_sort_item ) * (size_t) leaves );
	if ( load == NULL || costs == NULL )
	{
		free( load ), free( costs );
		return -1;
	}
	for ( long i = 0; i < leaves; ++i )
	{
		costs[i] = ( sere_sort_item ){ ~(uint64_t) leaf_cost( o, i ), (int32_t) i, 0 };
	}
	sere_sort_items( costs, (int32_t) leaves );
	for ( long k = 0; k < leaves; ++k )
	{
		int least = 0;
		for ( int r = 1; r < ranks; ++r )
		{
			least = load[r] < load[least] ? r : least;
		}
		order[k] = costs[k].index;
		owner[costs[k].index] = least;
		load[least] += (long) ~costs[k].key;
	}
	free( costs ), free( load );
	return 0;
}

static void litter_help( void )
{
	printf( "usage: sere litter --leaves N --seed S --out DIR [options]\n\n"
			"Dries N leaves lying on the ground (gravity_z = -9.8, ground at z = 0), each as sere run --until-dry\n"
			"dries it: until a layer has run dry (desiccated), or F frames. Each leaf's species and preset\n"
			"(maple/maple-red, maple/maple-green, plane/plane-tree, wisteria, grass), size, turn about z and place\n"
			"on the ground come from S and the leaf's index alone. Writes, in DIR:\n"
			"  leaves/leaf_NNNNN.ply  each leaf's final triangle layer in the scene, as soon as it is done\n"
			"                         (x, y, z, color, relative_water per vertex)\n"
			"  litter.ply             every leaf in index order, one mesh\n"
			"  litter.glb             the same as glTF 2.0 binary (positions, normals, colors, indices)\n"
			"  litter.png             the scene from an oblique camera, with the ground and shadows\n"
			"  summary.json           per leaf: index, species, preset, points, frames, desiccated, ms, status;\n"
			"                         totals\n\n"
			"A rerun into the same DIR with the same options keeps the leaves already written and gives the\n"
			"same litter.ply. A leaf that fails costs no other: it is reported (stderr, summary.json) and the\n"
			"command exits 1. A leaf takes up to 5,000 frames to dry (the red maple; the plane tree about 400), about\n"
			"1 to 3.5 ms a frame at 600 points on one core.\n\n"
			"options:\n"
			"  --leaves N    number of leaves (required)\n"
			"  --seed S      the scene's seed, a whole number >= 0 (default 1)\n"
			"  --out DIR     output directory (default out/litter)\n"
			"  --points P    triangle-layer points per leaf (default 600; the grass needs 390 for its outline and\n"
			"                veins, the plane tree 187: fewer fail those leaves, naming a count that builds)\n"
			"  --frames F    at most F frames per leaf, dry or not (default %d, twice what the slowest\n"
			"                species needs to dry; a leaf the default cap stops wet is reported on stderr)\n"
			"  --preset P    every leaf of this preset (maple-red, maple-green, plane-tree, wisteria, grass) instead\n"
			"                of a drawn one; the other draws stay the same\n"
			"  --threads T   leaves dried at once, threads bound to cores with hwloc (default: one per core)\n"
			"  --progress S  a line on stderr at most every S seconds with the leaves done and the time left\n"
			"                (default 60; 0: after every leaf)\n",
			LITTER_FRAME_CAP );
#ifdef SERE_MPI
	printf( "\nBuilt with MPI: under mpirun -np K the ranks share the leaves (dealt out by cost, the same every run)\n"
			"and rank 0 assembles the scene, the same as one process's. --threads is then per rank (default: the\n"
			"cores over the ranks on the machine); summary.json gives each leaf's rank and each rank's ms.\n" );
#endif
}

static const char* ply_vertex_properties = "property float x\nproperty float y\nproperty float z\n"
										   "property uchar red\nproperty uchar green\nproperty uchar blue\n"
										   "property float relative_water\n";

/* A PLY header for vertices and triangles with a comment line; the leaf files and litter.ply
 * share it, and reading a leaf file rebuilds it to check every byte. */
static int ply_header( char* out, size_t size, const char* comment, int32_t vertices, int32_t triangles )
{
	return snprintf( out, size,
					 "ply\nformat binary_little_endian 1.0\ncomment %s\nelement vertex %d\n%s"
					 "element face %d\nproperty list uchar int vertex_indices\nend_header\n",
					 comment, vertices, ply_vertex_properties, triangles );
}

/* Vertex records of 19 bytes (3 floats, 3 bytes, 1 float) then triangles of 13 (count 3 and
 * 3 ints, offset by base), little endian like every machine sere targets. */
static void ply_body( FILE* f, const litter_mesh* m )
{
	for ( int32_t i = 0; i < m->vertices; ++i )
	{
		float p[3] = { m->x[i], m->y[i], m->z[i] };
		fwrite( p, sizeof( float ), 3, f );
		fwrite( m->rgb + 3 * i, 1, 3, f );
		fwrite( m->rwc + i, sizeof( float ), 1, f );
	}
}

static void ply_faces( FILE* f, const litter_mesh* m, int32_t base )
{
	for ( int32_t t = 0; t < m->triangles; ++t )
	{
		uint8_t three = 3;
		int32_t v[3] = { m->tri[3 * t] + base, m->tri[3 * t + 1] + base, m->tri[3 * t + 2] + base };
		fwrite( &three, 1, 1, f );
		fwrite( v, sizeof( int32_t ), 3, f );
	}
}

/* The comment that ties a leaf file to the run options; frames and ms are what the summary
 * reports for a leaf kept from an earlier run. */
static void leaf_comment( char* out, size_t size, const litter_options* o, long index, long frames, int desiccated,
						  double ms )
{
	snprintf( out, size, "sere litter seed %ld leaf %ld preset %s points %ld frames_max %ld frames %ld dry %d ms %.3f",
			  o->seed, index, preset_names[draw_leaf( o, index ).species], o->points, o->frames, frames, desiccated,
			  ms );
}

static void leaf_path( char* out, size_t size, const litter_options* o, long index )
{
	snprintf( out, size, "%s/leaves/leaf_%05ld.ply", o->out, index );
}

/* Reads a leaf file written by this command with the same options; 0 with the mesh (when m
 * is not NULL), its frames and ms, or -1 when it is missing, cut short, or from other options. */
static int read_leaf( const litter_options* o, long index, litter_mesh* m, litter_result* r )
{
	char path[4200];
	leaf_path( path, sizeof( path ), o, index );
	FILE* f = fopen( path, "rb" );
	if ( f == NULL )
	{
		return -1;
	}
	char head[2048];
	size_t got = fread( head, 1, sizeof( head ) - 1, f );
	head[got] = '\0';
	char* end = strstr( head, "end_header\n" );
	long seed, leaf, points, frames_max, frames;
	int desiccated;
	char preset[32];
	double ms;
	int32_t vertices, triangles;
	struct stat info;
	if ( end == NULL || fstat( fileno( f ), &info ) != 0 ||
		 sscanf( head,
				 "ply\nformat binary_little_endian 1.0\ncomment sere litter seed %ld leaf %ld preset %31s points %ld "
				 "frames_max %ld frames %ld dry %d ms %lf\nelement vertex %d",
				 &seed, &leaf, preset, &points, &frames_max, &frames, &desiccated, &ms, &vertices ) != 9 ||
		 seed != o->seed || leaf != index || strcmp( preset, preset_names[draw_leaf( o, index ).species] ) != 0 ||
		 points != o->points || frames_max != o->frames || vertices < 3 )
	{
		fclose( f );
		return -1;
	}
	const char* face = strstr( head, "element face " );
	char expected[2048], comment[256];
	size_t header = (size_t) ( end - head ) + strlen( "end_header\n" );
	if ( face == NULL || sscanf( face, "element face %d", &triangles ) != 1 || triangles < 1 )
	{
		fclose( f );
		return -1;
	}
	leaf_comment( comment, sizeof( comment ), o, index, frames, desiccated, ms );
	/* every header byte as this command writes it, and exactly the body it announces */
	if ( (size_t) ply_header( expected, sizeof( expected ), comment, vertices, triangles ) != header ||
		 memcmp( expected, head, header ) != 0 ||
		 (long long) info.st_size != (long long) header + 19ll * vertices + 13ll * triangles )
	{
		fclose( f );
		return -1;
	}
	r->vertices = vertices, r->triangles = triangles, r->frames = frames, r->ms = ms;
	r->desiccated = desiccated;
	int failed = 0;
	if ( m != NULL )
	{
		failed = mesh_alloc( m, vertices, triangles ) != 0 || fseek( f, (long) header, SEEK_SET ) != 0;
		for ( int32_t i = 0; i < vertices && !failed; ++i )
		{
			float p[3];
			failed = fread( p, sizeof( float ), 3, f ) != 3 || fread( m->rgb + 3 * i, 1, 3, f ) != 3 ||
					 fread( m->rwc + i, sizeof( float ), 1, f ) != 1;
			m->x[i] = p[0], m->y[i] = p[1], m->z[i] = p[2];
		}
		for ( int32_t t = 0; t < triangles && !failed; ++t )
		{
			uint8_t three;
			failed =
				fread( &three, 1, 1, f ) != 1 || three != 3 || fread( m->tri + 3 * t, sizeof( int32_t ), 3, f ) != 3;
			for ( int k = 0; k < 3 && !failed; ++k )
			{
				failed = m->tri[3 * t + k] < 0 || m->tri[3 * t + k] >= vertices;
			}
		}
		if ( failed && m->x != NULL )
		{
			mesh_free( m );
		}
	}
	fclose( f );
	return failed ? -1 : 0;
}

static int leaf_fail( litter_result* r, const char* text )
{
	snprintf( r->error, sizeof( r->error ), "%s", text );
	r->state = LITTER_FAILED;
	return -1;
}

/* The built leaf dried as sere run dries it: face down when the preset says so, resting on
 * the ground, shaped (Jeong Sec. 3.1), then stepped until a layer ran dry (Sec. 6) or the cap.
 * *sim is the caller's to destroy, whatever the status. */
static sere_status dry_model( const litter_options* o, const sere_sim_params* params, sere_model* model,
							  sere_leaf_sim** sim, long* frames, int* desiccated )
{
	if ( params->face_down )
	{
		sere_model_mirror_z( model );
	}
	sere_model_rest_on( model, params->leaf.ground );
	*sim = NULL;
	sere_status status = sere_leaf_create( model, sim );
	/* One thread a leaf: the litter's parallelism is across leaves. */
	status = status == SERE_OK ? sere_leaf_set_threads( *sim, 1 ) : status;
	if ( status == SERE_OK && ( params->crease != 0.0f || params->curl != 0.0f ) )
	{
		/* Sec. 3.1, as sere run shapes a leaf before it dries */
		sere_pbd_params shaping = params->leaf.pbd;
		shaping.max_iterations = 2000;
		status = sere_leaf_shape_initial( *sim, params->crease, params->curl, &shaping );
	}
	/* sere run --until-dry's rule: on until a layer ran dry (Sec. 6), or the cap */
	long frame = 0;
	*desiccated = 0;
	while ( status == SERE_OK && frame < o->frames && !*desiccated )
	{
		sere_leaf_stats stats;
		status = sere_leaf_step( *sim, &params->leaf, &stats );
		frame += status == SERE_OK;
		*desiccated = status == SERE_OK && stats.desiccated;
	}
	*frames = frame;
	return status;
}

/* The dried leaf's triangle layer into the scene: scaled (z too, so it stays on the ground),
 * turned about z, moved, and colored by its relative water content (Jeong Sec. 6). */
static sere_status place_leaf( const litter_draw* d, const sere_model* model, const sere_leaf_sim* sim, litter_mesh* m )
{
	int32_t n = model->triangle_particles;
	if ( mesh_alloc( m, n, model->triangle_count ) != 0 )
	{
		return SERE_ERR_MEMORY;
	}
	float* rwc = malloc( sizeof( float ) * (size_t) model->p.capacity );
	if ( rwc == NULL )
	{
		return SERE_ERR_MEMORY;
	}
	sere_leaf_relative_water( sim, rwc );
	double c = cos( d->angle ), s = sin( d->angle );
	for ( int32_t i = 0; i < n; ++i )
	{
		double x = d->scale * model->p.x[i], y = d->scale * model->p.y[i];
		m->x[i] = (float) ( c * x - s * y + d->x );
		m->y[i] = (float) ( s * x + c * y + d->y );
		m->z[i] = (float) ( d->scale * model->p.z[i] );
		m->rwc[i] = rwc[i];
		float rgb[3];
		sere_render_dry_color( rwc[i], rgb );
		for ( int k = 0; k < 3; ++k )
		{
			m->rgb[3 * i + k] = (uint8_t) lrintf( 255.0f * rgb[k] );
		}
	}
	memcpy( m->tri, model->tri, sizeof( int32_t ) * 3 * (size_t) model->triangle_count );
	free( rwc );
	return SERE_OK;
}

/* A PLY file of m with comment in its header, written atomically; 0, or -1 with errno set. */
static int write_ply( const char* path, const char* comment, const litter_mesh* m )
{
	char header[2048];
	ply_header( header, sizeof( header ), comment, m->vertices, m->triangles );
	sere_atomic_file file;
	FILE* f = sere_atomic_open( &file, path );
	if ( f == NULL )
	{
		return -1;
	}
	fputs( header, f );
	ply_body( f, m );
	ply_faces( f, m, 0 );
	return sere_atomic_commit( &file );
}

/* The leaf's own PLY file, its run in the header comment; 0, or -1 with errno set. */
static int write_leaf( const litter_options* o, long index, const litter_result* r, const litter_mesh* m )
{
	char path[4200], comment[256];
	leaf_path( path, sizeof( path ), o, index );
	leaf_comment( comment, sizeof( comment ), o, index, r->frames, r->desiccated, r->ms );
	return write_ply( path, comment, m );
}

/* Dries leaf index as sere run would (harness/cli/cmd_run.c) on the ground, places it in the scene
 * and writes its file; 0, or -1 with the reason in r->error. */
static int dry_leaf( const litter_options* o, long index, litter_result* r )
{
	litter_draw d = draw_leaf( o, index );
	char err[4400], path[4200], name[128];
	snprintf( name, sizeof( name ), "leaf_%05ld.ply", index );
	char leaves_dir[4200];
	snprintf( leaves_dir, sizeof( leaves_dir ), "%s/leaves", o->out );
	const char* const names[] = { name };
	if ( sere_outputs_check( leaves_dir, names, 1, err, sizeof( err ) ) != 0 )
	{
		return leaf_fail( r, err );
	}
	sere_sim_params params = sere_sim_params_default();
	if ( sere_params_apply( &params, preset_names[d.species], NULL, 0, err, sizeof( err ) ) != 0 )
	{
		return leaf_fail( r, err );
	}
	/* the litter lies on the ground whatever the preset says: under gravity, on z = 0 */
	params.leaf.gravity[0] = 0.0f, params.leaf.gravity[1] = 0.0f, params.leaf.gravity[2] = -9.8f;
	params.leaf.ground = 0.0f;
	params.leaf.step_residual = 0; /* a litter writes no per-frame stats */
	params.seed = d.sample_seed;
	char relative[64];
	snprintf( relative, sizeof( relative ), "leaves/%s.leaf", species_names[d.species] );
	if ( sere_data_find( relative, path, sizeof( path ) ) != 0 )
	{
		snprintf( err, sizeof( err ), "cannot find %s (in SERE_DATA, ./data or the install prefix)", relative );
		return leaf_fail( r, err );
	}
	double start = sere_now();
	sere_model model;
	sere_build_report report;
	if ( sere_harness_build( path, -1, -1, o->points, &params, &model, &report, name, sizeof( name ), err,
							 sizeof( err ) ) != 0 )
	{
		return leaf_fail( r, err );
	}
	sere_leaf_sim* sim = NULL;
	long frame;
	int desiccated;
	sere_status status = dry_model( o, &params, &model, &sim, &frame, &desiccated );
	litter_mesh m = { 0 };
	status = status == SERE_OK ? place_leaf( &d, &model, sim, &m ) : status;
	sere_leaf_destroy( sim );
	sere_model_destroy( &model );
	if ( status != SERE_OK )
	{
		char why[256];
		command_step_error( &params, status, why, sizeof( why ) );
		snprintf( err, sizeof( err ), "frame %ld: %s", frame + 1, why );
		mesh_free( &m );
		return leaf_fail( r, err );
	}
	r->ms = 1000.0 * ( sere_now() - start );
	r->frames = frame;
	r->desiccated = desiccated;
	r->vertices = m.vertices, r->triangles = m.triangles;
	int failed = write_leaf( o, index, r, &m ) != 0;
	int error = errno;
	mesh_free( &m );
	if ( failed )
	{
		leaf_path( path, sizeof( path ), o, index );
		snprintf( err, sizeof( err ), "cannot write %s: %s", path, strerror( error ) );
		return leaf_fail( r, err );
	}
	r->state = LITTER_DRIED;
	return 0;
}

/* Appends a leaf's mesh to the scene's; 0, or -1 when out of memory. */
static int mesh_append( litter_mesh* scene, const litter_mesh* leaf )
{
	size_t n = (size_t) scene->vertices + (size_t) leaf->vertices;
	size_t t = (size_t) scene->triangles + (size_t) leaf->triangles;
	if ( n > INT32_MAX || t > INT32_MAX / 3 )
	{
		return -1;
	}
	float** fields[4] = { &scene->x, &scene->y, &scene->z, &scene->rwc };
	const float* from[4] = { leaf->x, leaf->y, leaf->z, leaf->rwc };
	for ( int k = 0; k < 4; ++k )
	{
		float* grown = realloc( *fields[k], sizeof( float ) * n );
		if ( grown == NULL )
		{
			return -1;
		}
		*fields[k] = grown;
		memcpy( grown + scene->vertices, from[k], sizeof( float ) * (size_t) leaf->vertices );
	}
	uint8_t* rgb = realloc( scene->rgb, 3 * n );
	int32_t* tri = rgb != NULL ? realloc( scene->tri, sizeof( int32_t ) * 3 * t ) : NULL;
	if ( rgb != NULL )
	{
		scene->rgb = rgb;
	}
	if ( tri == NULL )
	{
		return -1;
	}
	scene->tri = tri;
	memcpy( rgb + 3 * (size_t) scene->vertices, leaf->rgb, 3 * (size_t) leaf->vertices );
	for ( size_t k = 0; k < 3 * (size_t) leaf->triangles; ++k )
	{
		tri[3 * (size_t) scene->triangles + k] = leaf->tri[k] + scene->vertices;
	}
	scene->vertices = (int32_t) n, scene->triangles = (int32_t) t;
	return 0;
}

static int write_scene_ply( const char* path, const litter_options* o, const litter_mesh* scene )
{
	char comment[256];
	snprintf( comment, sizeof( comment ), "sere litter seed %ld leaves %ld preset %s points %ld frames_max %ld",
			  o->seed, o->leaves, o->species >= 0 ? preset_names[o->species] : "drawn", o->points, o->frames );
	return write_ply( path, comment, scene );
}

/* Where rank 0's time went, in seconds from the common start (the barrier after the deal). */
typedef struct litter_times
{
	double wall;   /* up to the summary: everything but the summary itself */
	double gather; /* from the slowest rank's end of drying to every result on rank 0 */
	double scene;  /* the leaf files read back into one scene; litter.ply, .glb and .png written */
} litter_times;

static int write_summary( const char* path, const litter_options* o, const litter_result* results, int bound, int ranks,
						  const double* rank_wall_ms, const litter_times* times, const litter_mesh* scene )
{
	sere_atomic_file file;
	FILE* f = sere_atomic_open( &file, path );
	if ( f == NULL )
	{
		return -1;
	}
	long dried = 0, resumed = 0, failed = 0, desiccated = 0;
	double ms = 0.0;
	fprintf( f,
			 "{\n  \"seed\": %ld,\n  \"points\": %ld,\n  \"frames_max\": %ld,\n  \"ranks\": %d,\n  \"threads\": %d,\n",
			 o->seed, o->points, o->frames, ranks, bound );
	fprintf( f, "  \"leaves\": [\n" );
	for ( long i = 0; i < o->leaves; ++i )
	{
		const litter_result* r = results + i;
		litter_draw d = draw_leaf( o, i );
		char status[6 * sizeof( r->error ) + 16];
		if ( r->state == LITTER_FAILED )
		{
			char escaped[6 * sizeof( r->error ) + 1];
			snprintf( status, sizeof( status ), "error: %s", sere_json_escape( escaped, sizeof( escaped ), r->error ) );
		}
		else
		{
			snprintf( status, sizeof( status ), "%s", r->state == LITTER_DRIED ? "dried" : "resumed" );
		}
		dried += r->state == LITTER_DRIED, resumed += r->state == LITTER_RESUMED, failed += r->state == LITTER_FAILED;
		desiccated += r->state != LITTER_FAILED && r->desiccated;
		ms += r->state == LITTER_FAILED ? 0.0 : r->ms;
		fprintf( f,
				 "    {\"index\": %ld, \"species\": \"%s\", \"preset\": \"%s\", \"scale\": %.6g, "
				 "\"angle\": %.6g, \"x\": %.6g, \"y\": %.6g, \"points\": %d, \"triangles\": %d, \"frames\": %ld, "
				 "\"desiccated\": %s, \"ms\": %.3f, \"rank\": %d, \"status\": \"%s\"}%s\n",
				 i, species_names[d.species], preset_names[d.species], d.scale, d.angle, d.x, d.y, r->vertices,
				 r->triangles, r->frames, r->state != LITTER_FAILED && r->desiccated ? "true" : "false",
				 r->state == LITTER_FAILED ? 0.0 : r->ms, r->rank, status, i + 1 < o->leaves ? "," : "" );
	}
	/* per rank: the ms of the leaves it dried now (resumed ones cost it nothing) and the wall
	 * time of its drying, whose spread says how evenly the leaves were dealt */
	fprintf( f, "  ],\n  \"ranks_ms\": [\n" );
	for ( int k = 0; k < ranks; ++k )
	{
		long count = 0;
		double leaf_ms = 0.0;
		for ( long i = 0; i < o->leaves; ++i )
		{
			count += results[i].rank == k;
			leaf_ms += results[i].rank == k && results[i].state == LITTER_DRIED ? results[i].ms : 0.0;
		}
		fprintf( f, "    {\"rank\": %d, \"leaves\": %ld, \"leaf_ms\": %.3f, \"wall_ms\": %.3f}%s\n", k, count, leaf_ms,
				 rank_wall_ms[k], k + 1 < ranks ? "," : "" );
	}
	fprintf( f,
			 "  ],\n  \"totals\": {\"leaves\": %ld, \"dried\": %ld, \"resumed\": %ld, \"failed\": %ld, "
			 "\"desiccated\": %ld, \"vertices\": %d, \"triangles\": %d, \"leaf_ms\": %.3f, \"wall_seconds\": %.3f, "
			 "\"gather_seconds\": %.3f, \"scene_seconds\": %.3f}\n}\n",
			 o->leaves, dried, resumed, failed, desiccated, scene->vertices, scene->triangles, ms, times->wall,
			 times->gather, times->scene );
	return sere_atomic_commit( &file );
}

/* --preset P: every leaf of that species; 0, or -1 with one line on stderr. */
/* Rank 0's progress through its share: the other ranks' shares cost about as much (dealt by
 * cost), so its share stands for the run's. */
typedef struct litter_progress
{
	double start, last;
	long leaves, done;
	long cost, cost_done;
} litter_progress;

/* A leaf of rank 0 is done: a line on stderr when --progress seconds have passed since the last,
 * with the time left estimated from the cost still to dry. */
static void progress_leaf( litter_progress* p, const litter_options* o, const litter_world* w, long cost )
{
	p->done += 1;
	p->cost_done += cost;
	double now = sere_now();
	if ( now - p->last < (double) o->progress || p->done == p->leaves )
	{
		return;
	}
	p->last = now;
	double minutes = ( now - p->start ) / 60.0;
	double left = p->cost_done > 0 ? minutes * (double) ( p->cost - p->cost_done ) / (double) p->cost_done : 0.0;
	char ranks[64] = "";
	if ( w->size > 1 )
	{
		snprintf( ranks, sizeof( ranks ), " on rank 0 of %d", w->size );
	}
	fprintf( stderr, "sere litter: %ld of %ld leaves%s done, %.1f min, about %.1f min left\n", p->done, p->leaves,
			 ranks, minutes, left );
}

/* This rank's leaves, one per thread, in dealing order (costliest first, so the cheap ones
 * fill in at the end): each reused from an earlier run's file, or dried. The leaves that failed. */
static long dry_share( const litter_options* o, const litter_world* w, const long* order, const int* owner,
					   litter_result* results, int bound, double start )
{
	litter_progress progress = { start, start, 0, 0, 0, 0 };
	for ( long i = 0; i < o->leaves; ++i )
	{
		progress.leaves += owner[i] == w->rank;
		progress.cost += owner[i] == w->rank ? leaf_cost( o, i ) : 0;
	}
#pragma omp parallel for schedule( dynamic, 1 ) num_threads( bound )
	for ( long k = 0; k < o->leaves; ++k )
	{
		long i = order[k];
		if ( owner[i] != w->rank )
		{
			continue;
		}
		litter_result* r = results + i;
		r->rank = w->rank;
		if ( read_leaf( o, i, NULL, r ) == 0 )
		{
			r->state = LITTER_RESUMED;
		}
		else if ( dry_leaf( o, i, r ) != 0 )
		{
			litter_draw d = draw_leaf( o, i );
			fprintf( stderr, "sere litter: leaf %ld (%s, %s) failed: %s\n", i, species_names[d.species],
					 preset_names[d.species], r->error );
		}
		if ( w->rank == 0 )
		{
#pragma omp critical( litter_progress )
			progress_leaf( &progress, o, w, leaf_cost( o, i ) );
		}
	}
	long failed = 0;
	for ( long i = 0; i < o->leaves; ++i )
	{
		failed += owner[i] == w->rank && results[i].state == LITTER_FAILED;
	}
	return failed;
}

/* The scene from the leaf files alone, in index order: a resumed run reads exactly the bytes an
 * uninterrupted one does, and so does a run on any number of ranks. The leaves that failed. */
static long read_scene( const litter_options* o, litter_result* results, litter_mesh* scene )
{
	long failed = 0;
	for ( long i = 0; i < o->leaves; ++i )
	{
		litter_result* r = results + i;
		litter_mesh leaf = { 0 };
		if ( r->state != LITTER_FAILED && ( read_leaf( o, i, &leaf, r ) != 0 || mesh_append( scene, &leaf ) != 0 ) )
		{
			char path[4200];
			leaf_path( path, sizeof( path ), o, i );
			snprintf( r->error, sizeof( r->error ), "cannot read back %s (changed during the run, or out of memory)",
					  path );
			r->state = LITTER_FAILED;
			fprintf( stderr, "sere litter: leaf %ld failed: %s\n", i, r->error );
		}
		mesh_free( &leaf );
		failed += r->state == LITTER_FAILED;
	}
	return failed;
}

/* litter.png: the scene seen from above at the longest-drying leaf's frame; with no leaf to
 * show, no picture of an earlier run is left beside this run's empty scene. 0, or -1 with a
 * message in err. */
static int write_scene_png( const char* path, const litter_options* o, const litter_result* results,
							const litter_mesh* scene, long failed, char* err, size_t err_size )
{
	if ( scene->vertices == 0 )
	{
		remove( path );
		return 0;
	}
	double water = 0.0;
	for ( int32_t i = 0; i < scene->vertices; ++i )
	{
		water += scene->rwc[i];
	}
	long frames = 0;
	for ( long i = 0; i < o->leaves; ++i )
	{
		frames = results[i].state != LITTER_FAILED && results[i].frames > frames ? results[i].frames : frames;
	}
	sere_leafpics_frame frame = {
		scene->x, scene->y, scene->z, scene->rwc, scene->vertices, (int) frames, water / scene->vertices
	};
	char title[160];
	snprintf( title, sizeof( title ), "litter: %ld leaves, seed %ld", o->leaves - failed, o->seed );
	return sere_leafpics_view( path, title, &frame, scene->tri, scene->triangles, 0.0f, 1200, err, err_size );
}

/* litter.ply, litter.glb and litter.png; 0, or 1 after printing what failed. */
static int write_scene_files( const litter_options* o, const litter_result* results, const litter_mesh* scene,
							  long failed )
{
	char path[4200], err[1024];
	int status = 0;
	snprintf( path, sizeof( path ), "%s/litter.ply", o->out );
	if ( write_scene_ply( path, o, scene ) != 0 )
	{
		fprintf( stderr, "sere litter: cannot write %s: %s\n", path, strerror( errno ) );
		status = 1;
	}
	snprintf( path, sizeof( path ), "%s/litter.glb", o->out );
	sere_glb_mesh glb = { scene->x, scene->y, scene->z, scene->rgb, scene->vertices, scene->tri, scene->triangles };
	if ( scene->vertices == 0 )
	{
		/* glTF has no empty mesh; and no scene of an earlier run is left beside this one */
		remove( path );
	}
	else if ( sere_glb_write( path, &glb, err, sizeof( err ) ) != 0 )
	{
		fprintf( stderr, "sere litter: %s\n", err );
		status = 1;
	}
	snprintf( path, sizeof( path ), "%s/litter.png", o->out );
	if ( write_scene_png( path, o, results, scene, failed, err, sizeof( err ) ) != 0 )
	{
		fprintf( stderr, "sere litter: %s\n", err );
		status = 1;
	}
	return status;
}

/* A chosen --frames stops leaves early on purpose; the default cap should not, so the leaves it
 * stopped before they dried are told on stderr. */
static void warn_wet( const litter_options* o, const litter_result* results )
{
	long wet = 0;
	for ( long i = 0; i < o->leaves; ++i )
	{
		wet += results[i].state != LITTER_FAILED && !results[i].desiccated;
	}
	if ( wet > 0 && !o->frames_given )
	{
		fprintf( stderr, "sere litter: %ld lea%s reached the %ld-frame cap before drying (--frames F raises it)\n", wet,
				 wet == 1 ? "f" : "ves", o->frames );
	}
}

int sere_cmd_litter( int argc, char** argv )
{
	litter_options o = { "out/litter", -1, 1, 600, LITTER_FRAME_CAP, -1, 0, 60 };
	long long leaves = -1, seed = 1, points = 600, frames = -1, threads = 0, progress_every = 60;
	const sere_option options[] = {
		{ "--leaves", SERE_OPTION_COUNT, &leaves, 1, 99999, NULL },
		{ "--seed", SERE_OPTION_COUNT, &seed, 0, (double) LONG_MAX, NULL },
		sere_option_out( &o.out ),
		sere_option_points( &points ),
		{ "--frames", SERE_OPTION_COUNT, &frames, 1, 100000000, NULL },
		{ "--preset", SERE_OPTION_CHOICE, &o.species, 0, 0, preset_names },
		sere_option_threads( &threads ),
		{ "--progress", SERE_OPTION_COUNT, &progress_every, 0, 86400, NULL },
	};
	int code = sere_options_read( "litter", argc, argv, options, sizeof( options ) / sizeof( options[0] ), NULL, NULL,
								  litter_help );
	if ( code != SERE_OPTIONS_GO )
	{
		return code;
	}
	o.leaves = (long) leaves, o.seed = (long) seed, o.points = (long) points, o.progress = (long) progress_every;
	o.frames_given = frames > 0;
	o.frames = frames > 0 ? (long) frames : o.frames;
	if ( o.leaves < 0 )
	{
		fprintf( stderr, "sere litter: missing --leaves N (see sere litter --help)\n" );
		return 2;
	}
	char path[4200], err[1024];
	snprintf( path, sizeof( path ), "%s/leaves", o.out );
	if ( sere_dir_create( path ) != 0 )
	{
		fprintf( stderr, "sere litter: cannot create %s: %s\n", path, strerror( errno ) );
		return 1;
	}
	static const char* const outputs[] = { "litter.ply", "litter.glb", "litter.png", "summary.json" };
	if ( sere_outputs_check( o.out, outputs, sizeof( outputs ) / sizeof( outputs[0] ), err, sizeof( err ) ) != 0 )
	{
		fprintf( stderr, "sere litter: %s\n", err );
		return 1;
	}
	litter_world w;
	if ( litter_world_init( &w ) != 0 )
	{
		fprintf( stderr, "sere litter: MPI did not start\n" );
		return 1;
	}
	litter_result* results = calloc( (size_t) o.leaves, sizeof( litter_result ) );
	long* order = malloc( sizeof( long ) * (size_t) o.leaves );
	int* owner = malloc( sizeof( int ) * (size_t) o.leaves );
	double* rank_wall_ms = malloc( sizeof( double ) * (size_t) w.size );
	if ( results == NULL || order == NULL || owner == NULL || rank_wall_ms == NULL ||
		 share_leaves( &o, w.size, order, owner ) != 0 )
	{
		fprintf( stderr, "sere litter: out of memory for %ld leaves\n", o.leaves );
		free( rank_wall_ms ), free( owner ), free( order ), free( results );
		return litter_world_abort( &w );
	}
	/* the ranks on this machine share its cores, each its own run of them, unless told */
	int per_rank = sere_topo_cores() / w.local_size;
	int team = threads > 0 ? (int) threads : per_rank > 0 ? per_rank : 1;
	int bound = sere_topo_bind_from( team, w.local_rank * team, NULL );
	/* one leaf per thread: the kernels' own regions then run on one thread each (their results
	 * do not depend on the count), and a small leaf is not cut into slivers of work */
	omp_set_max_active_levels( 1 );
	litter_world_barrier( &w );
	double start = sere_now();
	long failed = dry_share( &o, &w, order, owner, results, bound, start );
	if ( litter_world_gather( &w, results, order, owner, o.leaves, 1000.0 * ( sere_now() - start ), rank_wall_ms ) !=
		 0 )
	{
		fprintf( stderr, "sere litter: out of memory for %ld leaves\n", o.leaves );
		return litter_world_abort( &w );
	}
	double gathered = sere_now() - start, slowest = 0.0;
	for ( int r = 0; w.rank == 0 && r < w.size; ++r )
	{
		slowest = fmax( slowest, rank_wall_ms[r] / 1000.0 );
	}
	free( order ), free( owner );
	if ( w.rank != 0 )
	{
		free( rank_wall_ms ), free( results );
		return litter_world_finish( &w, failed > 0 );
	}
	litter_mesh scene = { 0 };
	failed = read_scene( &o, results, &scene );
	int status = failed > 0;
	warn_wet( &o, results );
	if ( write_scene_files( &o, results, &scene, failed ) != 0 )
	{
		status = 1;
	}
	double seconds = sere_now() - start;
	litter_times times = { seconds, gathered - slowest, seconds - gathered };
	snprintf( path, sizeof( path ), "%s/summary.json", o.out );
	if ( write_summary( path, &o, results, bound, w.size, rank_wall_ms, &times, &scene ) != 0 )
	{
		fprintf( stderr, "sere litter: cannot write %s: %s\n", path, strerror( errno ) );
		status = 1;
	}
	printf( "litter: %ld leaves (%ld failed), %d vertices, %d triangles, %.2f s on %d rank%s of %d thread%s\n",
			o.leaves, failed, scene.vertices, scene.triangles, seconds, w.size, w.size == 1 ? "" : "s", bound,
			bound == 1 ? "" : "s" );
	printf( "  %s/litter.ply, %s/litter.glb, %s/litter.png, %s/summary.json, leaves in %s/leaves\n", o.out, o.out,
			o.out, o.out, o.out );
	mesh_free( &scene );
	free( rank_wall_ms ), free( results );
	return litter_world_finish( &w, status );
}
