#define _POSIX_C_SOURCE 200809L
#include "build.h"
#include "commands.h"
#include "io.h"
#include "leaf.h"
#include "leafload.h"
#include "leafpics.h"
#include "machine.h"
#include "render.h"
#include "topo.h"
#include "watch.h"

#include <dirent.h>
#include <errno.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static volatile sig_atomic_t interrupted = 0;

static void on_signal( int signal_number )
{
	(void) signal_number;
	interrupted = 1;
}

static void run_help( void )
{
	printf( "usage: sere run LEAF --preset P --frames N --out DIR [options]\n\n"
			"Dries a leaf with Algorithm 1 and writes, in DIR:\n"
			"  frames/frame_NNNNN.ply  triangle layer with water, tau, relative water and vein (1 on a vein)\n"
			"                          per vertex (Blender, MeshLab)\n"
			"  frames/frame_NNNNN.vtp  the same as VTK PolyData; leaf.pvd is the ParaView time series\n"
			"  stats.csv               one row per frame: water per layer, area, max |C/l|, the step's residual and\n"
			"                          whether it converged, particles on the ground, edge-triangle crossings,\n"
			"                          drift of the area centroid and of the centre of mass (fresh lengths),\n"
			"                          ground gap, mean normal z and tilt, cross-section roll near the tip\n"
			"                          and the base, iterations, contacts (vertex-triangle and edge-edge\n"
			"                          found, unresolved), collision thickness, ms\n"
			"  summary.json            counts, parameters, the Table 1 breakdown (mean ms per frame), the frame\n"
			"                          rule, the run's worst crossings/drift/tilt/gap, which end rolled first,\n"
			"                          the fresh and dry shape measures, the machine\n"
			"  drying3d.png            fresh, middle and dry leaf in 3D (oblique, ground, shadow) over the top view\n"
			"  leaf3d.png              the last frame in 3D, larger\n"
			"  drying.png              contact sheet of the drying sequence colored by relative water content\n"
			"  curves.png              relative water content and leaf area over time\n\n"
			"options:\n"
			"  --preset P        maple-green, maple-red, plane-tree, wisteria, grass, or a preset file\n"
			"  --frames N        frames to simulate (default 400)\n"
			"  --out DIR         output directory (default out/run)\n"
			"  --every K         write a mesh frame every K frames (default: about 24 frames in all)\n"
			"  --points N        triangle-layer points (default 1500; a leaf needs enough for its outline and veins,\n"
			"                    the error names a count that builds); or --particles P --springs S exactly\n"
			"  --threads T       OpenMP threads, bound to cores with hwloc (default: one per core)\n"
			"  --set key=value   override a parameter; keys:\n" );
	sere_params_describe( stdout );
	printf( "Interrupting (Ctrl-C) stops after the current frame and still writes the summary and pictures.\n" );
}

static int parse_long( const char* option, const char* text, long long lo, long long hi, long long* value )
{
	char* end;
	long long v = strtoll( text, &end, 10 );
	if ( *text == '\0' || *end != '\0' || v < lo || v > hi )
	{
		fprintf( stderr, "sere run: %s takes a whole number from %lld to %lld, not '%s'\n", option, lo, hi, text );
		return -1;
	}
	*value = v;
	return 0;
}

sere_leaf_params sere_run_leaf_params( const sere_sim_params* s )
{
	sere_leaf_params p = sere_leaf_params_default();
	p.dt = (float) s->dt;
	p.gravity[0] = (float) s->gravity[0];
	p.gravity[1] = (float) s->gravity[1];
	p.gravity[2] = (float) s->gravity[2];
	p.ground = (float) s->ground;
	p.damping = (float) s->damping;
	p.water_rate_t = s->water_rate_t;
	p.water_rate_v = s->water_rate_v;
	p.osmosis.lambda_min = s->lambda_min;
	p.osmosis.lambda_max = s->lambda_max;
	p.osmosis.mode = s->conservative != 0.0 ? SERE_OSMOSIS_CONSERVATIVE : SERE_OSMOSIS_PAPER;
	p.shrink.sigma_vein = s->sigma_vein;
	p.shrink.sigma_surf = s->sigma_surf;
	p.shrink.alpha = s->alpha;
	p.shrink.m_min = s->layer.m_min;
	p.shrink.min_length_ratio = s->min_length_ratio;
	p.pbd.stiffness = (float) s->stiffness;
	p.pbd.tolerance = (float) s->strain_tolerance;
	p.pbd.max_iterations = (int32_t) s->max_iterations;
	p.pbd.compliance = (float) s->compliance;
	p.vein_compliance = (float) s->vein_compliance;
	p.voronoi_compliance = (float) s->voronoi_compliance;
	p.local_stop = s->local_stop != 0.0;
	p.link_compliance = (float) s->link_compliance;
	p.friction_static = (float) s->friction_static;
	p.friction_kinetic = (float) s->friction_kinetic;
	p.pbd_stall = (float) s->pbd_stall;
	p.pbd.chebyshev_rho = (float) s->chebyshev_rho;
	p.collide.thickness = (float) s->collision_thickness;
	p.collisions = s->collision_thickness > 0.0;
	p.scale_thickness = s->collision_scaling != 0.0;
	p.restore_measured = s->restore_measured != 0.0;
	p.soften = s->soften != 0.0;
	return p;
}

static double leaf_area( const sere_model* model )
{
	const sere_particles* p = &model->p;
	double area = 0.0;
	for ( int32_t t = 0; t < model->triangle_count; ++t )
	{
		const int32_t* v = model->tri + 3 * t;
		double ax = p->x[v[1]] - p->x[v[0]], ay = p->y[v[1]] - p->y[v[0]], az = p->z[v[1]] - p->z[v[0]];
		double bx = p->x[v[2]] - p->x[v[0]], by = p->y[v[2]] - p->y[v[0]], bz = p->z[v[2]] - p->z[v[0]];
		double nx = ay * bz - az * by, ny = az * bx - ax * bz, nz = ax * by - ay * bx;
		area += 0.5 * sqrt( nx * nx + ny * ny + nz * nz );
	}
	return area;
}

/* A kept snapshot for the contact sheet. */
typedef struct snapshot
{
	float *x, *y, *z, *rwc;
	long long frame;
	double relative_water;
	char caption[96];
} snapshot;

/* Writes frame's PLY and VTP files and adds the VTP to leaf.pvd; 0, or -1 with "cannot write
 * PATH: reason" in err. */
static int write_frame( const char* out, int frame, double time, const sere_model* model, const float* rwc,
						sere_pvd_series* pvd, char* err, size_t err_size )
{
	const sere_particles* p = &model->p;
	int32_t n = model->triangle_particles;
	float* water = malloc( 2 * sizeof( float ) * (size_t) n );
	if ( water == NULL )
	{
		snprintf( err, err_size, "frame %d: out of memory", frame );
		return -1;
	}
	float* vein = water + n;
	for ( int32_t i = 0; i < n; ++i )
	{
		water[i] = (float) p->w[i];
		vein[i] = model->vein[i] ? 1.0f : 0.0f;
	}
	sere_vertex_property properties[4] = {
		{ "water", water }, { "tau", p->tau }, { "relative_water", rwc }, { "vein", vein }
	};
	char path[4096];
	snprintf( path, sizeof( path ), "%s/frames/frame_%05d.ply", out, frame );
	int failed = sere_write_ply( path, p->x, p->y, p->z, n, model->tri, model->triangle_count, NULL, properties, 4 );
	if ( !failed )
	{
		snprintf( path, sizeof( path ), "%s/frames/frame_%05d.vtp", out, frame );
		failed = sere_write_vtp( path, p->x, p->y, p->z, n, model->tri, model->triangle_count, properties, 4 );
		if ( failed )
		{
			/* no half frame: the PLY goes too, which on a full disk leaves room for the summary */
			int error = errno;
			char ply[4096];
			snprintf( ply, sizeof( ply ), "%s/frames/frame_%05d.ply", out, frame );
			remove( ply );
			errno = error;
		}
	}
	int error = errno;
	free( water );
	if ( failed )
	{
		snprintf( err, err_size, "cannot write %s: %s", path, strerror( error ) );
		return -1;
	}
	char name[64];
	snprintf( name, sizeof( name ), "frames/frame_%05d.vtp", frame );
	snprintf( path, sizeof( path ), "%s/leaf.pvd", out );
	if ( sere_pvd_append( pvd, path, name, time ) != 0 )
	{
		snprintf( err, err_size, "cannot write %s: %s", path, strerror( errno ) );
		return -1;
	}
	return 0;
}

/* The contact sheet: every panel at frame 0's scale, centred on its own leaf so a drifting
 * leaf stays in view while its shrinking shows, colored by the paper's fresh-to-dry blend. */
typedef struct sheet_context
{
	const snapshot* shots;
	const int32_t* tri;
	int32_t triangle_count;
	int32_t vertex_count;
	float* rgb;
	sere_render_view view;
} sheet_context;

static int draw_panel( void* user, int index, cairo_t* cr, double x, double y, double w, double h, char* caption,
					   size_t caption_size, char* err, size_t err_size )
{
	sheet_context* c = user;
	const snapshot* s = c->shots + index;
	sere_render_dry_colors( s->rwc, c->vertex_count, c->rgb );
	sere_render_mesh mesh = { s->x, s->y, s->z, c->vertex_count, c->tri, c->triangle_count, c->rgb, NULL, { 0, 0, 0 } };
	if ( index > 0 )
	{
		double centre[3] = { 0.0, 0.0, 0.0 };
		for ( int32_t i = 0; i < c->vertex_count; ++i )
		{
			centre[0] += s->x[i], centre[1] += s->y[i], centre[2] += s->z[i];
		}
		for ( int k = 0; k < 3; ++k )
		{
			c->view.center[k] = centre[k] / c->vertex_count;
		}
	}
	snprintf( caption, caption_size, "%s", s->caption );
	return sere_render_mesh_draw( cr, x, y, w, h, &mesh, &c->view, NULL, err, err_size );
}

/* A run into a directory used before replaces its frames: frame_NNNNN.ply/.vtp left by a longer
 * or differently spaced run would otherwise sit among the new ones (leaf.pvd lists only the
 * new). Only names this command writes are removed. */
static void remove_old_frames( const char* frames_dir )
{
	DIR* dir = opendir( frames_dir );
	if ( dir == NULL )
	{
		return;
	}
	struct dirent* entry;
	while ( ( entry = readdir( dir ) ) != NULL )
	{
		int number = 0, length = 0;
		char ext[4] = { 0 };
		if ( sscanf( entry->d_name, "frame_%5d.%3[a-z]%n", &number, ext, &length ) == 2 &&
			 length == (int) strlen( entry->d_name ) && strlen( entry->d_name ) == 15 &&
			 ( strcmp( ext, "ply" ) == 0 || strcmp( ext, "vtp" ) == 0 ) )
		{
			char path[4096 + 32];
			snprintf( path, sizeof( path ), "%.4095s/%.16s", frames_dir, entry->d_name );
			remove( path );
		}
	}
	closedir( dir );
}

/* A JSON number, or null for NaN and infinities (JSON has neither). */
static void json_number( FILE* f, double value )
{
	if ( isfinite( value ) )
	{
		fprintf( f, "%.6g", value );
	}
	else
	{
		fprintf( f, "null" );
	}
}

/* The shape measures of kernels/measure.h as a JSON object member. */
static void print_shape( FILE* f, const char* key, const sere_shape* shape, double length )
{
	const char* names[] = { "area",			 "extent",		   "extent_per_fresh_length",
							"min_z",		 "max_z",		   "ground_gap",
							"crease_vein",	 "crease_surf",	   "margin_lift",
							"roll_tip",		 "roll_base",	   "curl_tip",
							"curl_base",	 "crease_main",	   "crease_blade",
							"vein_roll_tip", "vein_roll_base", "normal_x",
							"normal_y",		 "normal_z" };
	const double values[] = { shape->area,			 shape->extent,			shape->extent / length,
							  shape->min_z,			 shape->max_z,			shape->ground_gap,
							  shape->crease_vein,	 shape->crease_surf,	shape->margin_lift,
							  shape->roll_tip,		 shape->roll_base,		shape->curl_tip,
							  shape->curl_base,		 shape->crease_main,	shape->crease_blade,
							  shape->vein_roll_tip,	 shape->vein_roll_base, shape->mean_normal[0],
							  shape->mean_normal[1], shape->mean_normal[2] };
	fprintf( f, "  \"%s\": {", key );
	for ( size_t k = 0; k < sizeof( values ) / sizeof( values[0] ); ++k )
	{
		fprintf( f, "%s\"%s\": ", k > 0 ? ", " : "", names[k] );
		json_number( f, values[k] );
	}
	fprintf( f, ", \"wrinkle_sign_changes\": %lld, \"flip\": %s},\n", (long long) shape->wrinkle_sign_changes,
			 shape->flip ? "true" : "false" );
}

int sere_cmd_run( int argc, char** argv )
{
	const char* path = NULL;
	const char* preset = NULL;
	const char* out = "out/run";
	long long frames = 400, every = 0, points = 1500, particles = -1, springs = -1, threads = 0;
	char err[1024];
	int until_dry = 0;
	sere_sim_params params = sere_sim_params_default();
	const char* sets[64];
	int set_count = 0;
	for ( int i = 1; i < argc; ++i )
	{
		const char* a = argv[i];
		if ( strcmp( a, "--help" ) == 0 || strcmp( a, "-h" ) == 0 )
		{
			run_help();
			return 0;
		}
		if ( strcmp( a, "--until-dry" ) == 0 )
		{
			until_dry = 1;
			continue;
		}
		static const char* const valued[] = { "--preset", "--out",		 "--set",	  "--frames", "--every",
											  "--points", "--particles", "--springs", "--threads" };
		int takes_value = 0;
		for ( size_t k = 0; k < sizeof( valued ) / sizeof( valued[0] ); ++k )
		{
			takes_value |= strcmp( a, valued[k] ) == 0;
		}
		if ( takes_value && i + 1 >= argc )
		{
			fprintf( stderr, "sere run: %s needs a value (see sere run --help)\n", a );
			return 2;
		}
		if ( strcmp( a, "--preset" ) == 0 )
		{
			preset = argv[++i];
		}
		else if ( strcmp( a, "--out" ) == 0 )
		{
			out = argv[++i];
			if ( sere_parse_dir( "run", a, out ) != 0 )
				return 2;
		}
		else if ( strcmp( a, "--set" ) == 0 )
		{
			if ( set_count == 64 )
			{
				fprintf( stderr, "sere run: at most 64 --set options\n" );
				return 2;
			}
			sets[set_count++] = argv[++i];
		}
		else if ( strcmp( a, "--frames" ) == 0 )
		{
			if ( parse_long( a, argv[++i], 1, 100000000, &frames ) != 0 )
				return 2;
		}
		else if ( strcmp( a, "--every" ) == 0 )
		{
			if ( parse_long( a, argv[++i], 1, 100000000, &every ) != 0 )
				return 2;
		}
		else if ( strcmp( a, "--points" ) == 0 )
		{
			if ( parse_long( a, argv[++i], 10, 10000000, &points ) != 0 )
				return 2;
		}
		else if ( strcmp( a, "--particles" ) == 0 )
		{
			if ( parse_long( a, argv[++i], 4, 100000000, &particles ) != 0 )
				return 2;
		}
		else if ( strcmp( a, "--springs" ) == 0 )
		{
			if ( parse_long( a, argv[++i], 1, 400000000, &springs ) != 0 )
				return 2;
		}
		else if ( strcmp( a, "--threads" ) == 0 )
		{
			if ( parse_long( a, argv[++i], 0, 256, &threads ) != 0 )
				return 2;
		}
		else if ( a[0] == '-' )
		{
			fprintf( stderr, "sere run: unknown option '%s' (see sere run --help)\n", a );
			return 2;
		}
		else if ( path == NULL )
		{
			path = a;
		}
		else
		{
			fprintf( stderr, "sere run: one LEAF only, got '%s' and '%s'\n", path, a );
			return 2;
		}
	}
	if ( path == NULL )
	{
		fprintf( stderr, "sere run: missing LEAF (a .leaf file; see sere run --help)\n" );
		return 2;
	}
	if ( ( particles < 0 ) != ( springs < 0 ) )
	{
		fprintf( stderr, "sere run: --particles and --springs go together\n" );
		return 2;
	}
	if ( sere_params_apply( &params, preset, sets, set_count, err, sizeof( err ) ) != 0 )
	{
		fprintf( stderr, "sere run: %s\n", err );
		return 2;
	}
	if ( every == 0 )
	{
		every = frames / 24 > 0 ? frames / 24 : 1;
	}
	int bound = sere_topo_bind( (int) threads, NULL );

	sere_model model;
	sere_build_report report;
	char name[128];
	if ( sere_harness_build( path, particles, springs, points, &params, &model, &report, name, sizeof( name ), err,
							 sizeof( err ) ) != 0 )
	{
		fprintf( stderr, "sere run: %s\n", err );
		return 1;
	}
	char frames_dir[4096];
	snprintf( frames_dir, sizeof( frames_dir ), "%s/frames", out );
	if ( sere_mkdirs( frames_dir ) != 0 )
	{
		fprintf( stderr, "sere run: cannot create %s: %s\n", frames_dir, strerror( errno ) );
		sere_model_destroy( &model );
		return 1;
	}
	static const char* const outputs[] = { "stats.csv",	 "summary.json", "leaf.pvd",  "drying.png",
										   "curves.png", "drying3d.png", "leaf3d.png" };
	if ( sere_check_outputs( out, outputs, sizeof( outputs ) / sizeof( outputs[0] ), err, sizeof( err ) ) != 0 )
	{
		fprintf( stderr, "sere run: %s\n", err );
		sere_model_destroy( &model );
		return 1;
	}
	remove_old_frames( frames_dir );
	if ( params.face_down != 0.0 )
	{
		sere_model_mirror_z( &model );
	}
	sere_model_rest_on( &model, (float) params.ground );
	sere_leaf_sim* sim = NULL;
	sere_status status = sere_leaf_create( &model, &sim );
	if ( status != SERE_OK )
	{
		fprintf( stderr, "sere run: %s\n", sere_status_text( status ) );
		sere_model_destroy( &model );
		return 1;
	}
	sere_leaf_params leaf = sere_run_leaf_params( &params );
	/* the fresh shape, and a watch on crossings, drift, the ground and turning over */
	sere_shape shape_fresh, shape_dry;
	sere_shape_input shape_input = sere_leaf_shape_input( &model, params.ground );
	/* the leaf's veins in its own plane (the model's fresh u, v), for the measures along and
	 * across its main veins; the build above has already read the same file */
	sere_leaf veins;
	bool have_veins = sere_leaf_load( path, &veins, err, sizeof( err ) ) == 0;
	shape_input.veins = have_veins ? &veins.file.shape : NULL;
	sere_watch* watch = NULL;
	status = sere_shape_measure( &shape_input, &shape_fresh );
	if ( status == SERE_OK )
	{
		status = sere_watch_create( &model, params.ground, &watch );
	}
	if ( status != SERE_OK )
	{
		fprintf( stderr, "sere run: cannot measure the fresh leaf: %s\n", sere_status_text( status ) );
		if ( have_veins )
		{
			sere_leaf_free( &veins );
		}
		sere_leaf_destroy( sim );
		sere_model_destroy( &model );
		return 1;
	}
	shape_dry = shape_fresh;
	sere_watch_frame watched = { 0, 0.0, 0.0, NAN, 1.0, 0.0, NAN, NAN };
	long long converged = 0, crossing_frames = 0;
	int64_t crossings_max = 0;
	/* the first frames whose tip and base sections have rolled by ROLL_ONSET: which end rolls first */
	const double ROLL_ONSET = 0.5;
	long long onset_tip = -1, onset_base = -1;
	double drift_max = 0.0, mass_drift_max = 0.0, gap_max = -INFINITY, tilt_max = 0.0;
	if ( params.crease != 0.0 || params.curl != 0.0 )
	{
		/* Sec. 3.1: creases along the veins and a curled blade before drying starts. */
		sere_pbd_params shaping = leaf.pbd;
		shaping.max_iterations = 2000;
		status = sere_leaf_shape_initial( sim, (float) params.crease, (float) params.curl, &shaping );
		if ( status != SERE_OK )
		{
			fprintf( stderr, "sere run: initial shaping: %s\n", sere_status_text( status ) );
			if ( have_veins )
			{
				sere_leaf_free( &veins );
			}
			sere_watch_destroy( watch );
			sere_leaf_destroy( sim );
			sere_model_destroy( &model );
			return 1;
		}
	}

	int32_t n = model.triangle_particles;
	float* rwc = malloc( sizeof( float ) * (size_t) model.p.capacity );
	enum
	{
		sheet_panels = 12
	};
	snapshot shots[sheet_panels] = { 0 };
	int shot_count = 0;
	long long shot_every = 1;
	double* curve_t = malloc( sizeof( double ) * (size_t) ( frames + 1 ) );
	double* curve_rwc = malloc( sizeof( double ) * (size_t) ( frames + 1 ) );
	double* curve_area = malloc( sizeof( double ) * (size_t) ( frames + 1 ) );
	sere_pvd_series pvd = { 0 }; /* the mesh frames written, for leaf.pvd */
	if ( !rwc || !curve_t || !curve_rwc || !curve_area )
	{
		fprintf( stderr, "sere run: out of memory\n" );
		return 1;
	}
	sere_atomic_file csv_file;
	char csv_path[4096];
	snprintf( csv_path, sizeof( csv_path ), "%s/stats.csv", out );
	FILE* csv = sere_atomic_open( &csv_file, csv_path );
	if ( csv == NULL )
	{
		fprintf( stderr, "sere run: cannot write %s: %s\n", csv_path, strerror( errno ) );
		return 1;
	}
	fprintf( csv, "frame,time,water_t,water_v,relative_water,area,relative_area,max_strain,residual,converged,"
				  "grounded,crossings,drift,mass_drift,ground_gap,normal_z,tilt,roll_tip,roll_base,cg_iterations_t,"
				  "cg_iterations_v,pbd_iterations,pbd_hit_cap,pbd_stalled,contacts,edge_contacts,unresolved,thickness,"
				  "desiccated,"
				  "osmosis_ms,dynamics_ms,"
				  "collisions_ms,"
				  "total_ms\n" );

	signal( SIGINT, on_signal );
	signal( SIGTERM, on_signal );
	signal( SIGXFSZ, SIG_IGN ); /* past a file-size limit a write fails (EFBIG) and is reported */
	double area0 = leaf_area( &model );
	sere_leaf_relative_water( sim, rwc );
	char failure[4400] = ""; /* the first output error; the run stops there */
	if ( write_frame( out, 0, 0.0, &model, rwc, &pvd, failure, sizeof( failure ) ) != 0 )
	{
		fprintf( stderr, "sere run: %s\n", failure );
	}
	curve_t[0] = 0.0, curve_rwc[0] = 1.0, curve_area[0] = 1.0;
	double sum_osmosis = 0, sum_dynamics = 0, sum_collisions = 0, sum_total = 0;
	long long done = 0, cap_hits = 0, stalls = 0;
	int32_t max_pbd_iterations = 0;
	sere_leaf_stats stats = { 0 };
	sere_progress progress;
	sere_progress_begin( &progress, "drying", frames );
	/* the first contact-sheet panel: the fresh leaf */
	for ( long long frame = 0; frame <= frames && !interrupted && failure[0] == '\0'; ++frame )
	{
		if ( frame > 0 )
		{
			sere_leaf_stats next;
			status = sere_leaf_step( sim, &leaf, &next );
			if ( status == SERE_OK )
			{
				stats = next;
			}
			else
			{
				fprintf( stderr, "\nsere run: frame %lld: %s\n", frame, sere_status_text( status ) );
				break;
			}
			done = frame;
			sum_osmosis += stats.osmosis_ms, sum_dynamics += stats.dynamics_ms;
			sum_collisions += stats.collisions_ms, sum_total += stats.total_ms;
			cap_hits += stats.pbd_hit_cap;
			stalls += stats.pbd_stalled;
			max_pbd_iterations = stats.pbd_iterations > max_pbd_iterations ? stats.pbd_iterations : max_pbd_iterations;
			status = sere_watch_step( watch, &model, &watched );
			if ( status != SERE_OK )
			{
				fprintf( stderr, "\nsere run: frame %lld: cannot measure: %s\n", frame, sere_status_text( status ) );
				break;
			}
			converged += stats.pbd_converged;
			crossing_frames += watched.crossings > 0;
			crossings_max = watched.crossings > crossings_max ? watched.crossings : crossings_max;
			drift_max = fmax( drift_max, watched.drift );
			mass_drift_max = fmax( mass_drift_max, watched.mass_drift );
			gap_max = fmax( gap_max, watched.ground_gap );
			tilt_max = fmax( tilt_max, watched.tilt_degrees );
			onset_tip = onset_tip < 0 && fabs( watched.roll_tip ) >= ROLL_ONSET ? frame : onset_tip;
			onset_base = onset_base < 0 && fabs( watched.roll_base ) >= ROLL_ONSET ? frame : onset_base;
			double area = leaf_area( &model );
			curve_t[frame] = frame * params.dt;
			curve_rwc[frame] = stats.relative_water;
			curve_area[frame] = area / area0;
			fprintf( csv,
					 "%lld,%.6g,%.9g,%.9g,%.6g,%.9g,%.6g,%.6g,%.6g,%d,%d,%lld,%.6g,%.6g,%.6g,%.6g,%.4g,%.4g,%.4g,"
					 "%d,%d,%d,%d,%d,%d,%d,%d,%.6g,%d,%.4f,%.4f,%.4f,%.4f\n",
					 frame, frame * params.dt, stats.water_t, stats.water_v, stats.relative_water, area, area / area0,
					 stats.max_strain, stats.residual, stats.pbd_converged, stats.grounded,
					 (long long) watched.crossings, watched.drift, watched.mass_drift, watched.ground_gap,
					 watched.normal_z, watched.tilt_degrees, watched.roll_tip, watched.roll_base, stats.cg_iterations_t,
					 stats.cg_iterations_v, stats.pbd_iterations, stats.pbd_hit_cap, stats.pbd_stalled, stats.contacts,
					 stats.edge_contacts, stats.unresolved, stats.collision_thickness, stats.desiccated,
					 stats.osmosis_ms, stats.dynamics_ms, stats.collisions_ms, stats.total_ms );
			if ( fflush( csv ) != 0 )
			{
				snprintf( failure, sizeof( failure ), "cannot write %s: %s", csv_path, strerror( errno ) );
				fprintf( stderr, "%ssere run: %s\n", progress.active ? "\n" : "", failure );
				break;
			}
			sere_leaf_relative_water( sim, rwc );
			if ( frame % every == 0 || frame == frames )
			{
				if ( write_frame( out, (int) frame, frame * params.dt, &model, rwc, &pvd, failure,
								  sizeof( failure ) ) != 0 )
				{
					fprintf( stderr, "%ssere run: %s\n", progress.active ? "\n" : "", failure );
					break;
				}
			}
		}
		int last = frame == frames || ( until_dry && stats.desiccated );
		if ( frame % shot_every == 0 || last )
		{
			/* Keep at most sheet_panels evenly spaced panels whatever the run's length: when full,
			 * drop every other one and take them half as often. */
			if ( shot_count == sheet_panels )
			{
				for ( int k = 1; k < sheet_panels; k += 2 )
				{
					free( shots[k].x ), free( shots[k].y ), free( shots[k].z ), free( shots[k].rwc );
				}
				for ( int k = 0; k < sheet_panels / 2; ++k )
				{
					shots[k] = shots[2 * k];
				}
				shot_count = sheet_panels / 2;
				shot_every *= 2;
			}
			if ( frame % shot_every == 0 || last )
			{
				/* The final state replaces a panel less than half a spacing before it, so the
				 * sheet never ends on two near-identical pictures. */
				if ( last && shot_count > 1 && 2 * ( frame - shots[shot_count - 1].frame ) < shot_every )
				{
					snapshot* previous = shots + --shot_count;
					free( previous->x ), free( previous->y ), free( previous->z ), free( previous->rwc );
				}
				snapshot* s = shots + shot_count++;
				s->frame = frame;
				s->relative_water = stats.relative_water;
				size_t bytes = sizeof( float ) * (size_t) n;
				s->x = malloc( bytes ), s->y = malloc( bytes ), s->z = malloc( bytes ), s->rwc = malloc( bytes );
				memcpy( s->x, model.p.x, bytes ), memcpy( s->y, model.p.y, bytes ), memcpy( s->z, model.p.z, bytes );
				memcpy( s->rwc, rwc, bytes );
				snprintf( s->caption, sizeof( s->caption ), "frame %lld, water %.0f%%", frame,
						  100.0 * ( frame > 0 ? stats.relative_water : 1.0 ) );
			}
		}
		sere_progress_update( &progress, frame );
		if ( until_dry && stats.desiccated )
		{
			if ( frame % every != 0 && write_frame( out, (int) frame, frame * params.dt, &model, rwc, &pvd, failure,
													sizeof( failure ) ) != 0 )
			{
				fprintf( stderr, "%ssere run: %s\n", progress.active ? "\n" : "", failure );
			}
			break;
		}
	}
	sere_progress_end( &progress );
	int stopped = failure[0] != '\0'; /* an output error ended the loop */
	if ( sere_atomic_commit( &csv_file ) != 0 && !stopped )
	{
		snprintf( failure, sizeof( failure ), "cannot write %s: %s", csv_path, strerror( errno ) );
		fprintf( stderr, "sere run: %s\n", failure );
	}

	if ( done > 0 )
	{
		shape_input = sere_leaf_shape_input( &model, params.ground );
		shape_input.veins = have_veins ? &veins.file.shape : NULL;
		if ( sere_shape_measure( &shape_input, &shape_dry ) != SERE_OK )
		{
			shape_dry = shape_fresh;
		}
	}

	/* Pictures. */
	char picture[4096];
	sheet_context sheet_user = {
		shots, model.tri, model.triangle_count, n, NULL, { -35.0, 50.0, { 0, 0, 0 }, 0.0, 8.0 }
	};
	sheet_user.rgb = malloc( sizeof( float ) * 3 * (size_t) n );
	char title[256];
	snprintf( title, sizeof( title ), "%s, preset %s: drying colored by relative water content", name,
			  preset ? preset : "default" );
	snprintf( picture, sizeof( picture ), "%s/drying.png", out );
	sere_render_sheet sheet = { title, 4, shot_count, 320, 300, draw_panel, &sheet_user };
	int picture_failed =
		sheet_user.rgb == NULL || sere_render_contact_sheet( picture, &sheet, err, sizeof( err ) ) != 0;
	free( sheet_user.rgb );
	sere_render_series curves[2] = {
		{ "relative water content", curve_t, curve_rwc, (int32_t) done + 1, { 0.0f, 0.45f, 0.70f }, 0 },
		{ "relative leaf area", curve_t, curve_area, (int32_t) done + 1, { 0.55f, 0.36f, 0.17f }, 0 }
	};
	snprintf( title, sizeof( title ), "%s, preset %s: relative water content and leaf area", name,
			  preset ? preset : "default" );
	sere_render_axes axes = { title, "time", "fraction of initial", 1, 0.0, 1.05 };
	snprintf( picture, sizeof( picture ), "%s/curves.png", out );
	picture_failed = picture_failed || sere_render_plot( picture, 800, 480, &axes, curves, 2, err, sizeof( err ) ) != 0;
	/* The shape in 3D (Fig. 17 (a)-(b)): fresh, middle and dry from an oblique camera with the
	 * ground and the shadow, above the top view; then the dry leaf alone, larger. */
	if ( shot_count > 0 )
	{
		const int picks[3] = { 0, shot_count / 2, shot_count - 1 };
		sere_leafpics_frame views[3];
		int view_count = 0;
		for ( int k = 0; k < 3; ++k )
		{
			if ( k > 0 && picks[k] == picks[k - 1] )
			{
				continue;
			}
			const snapshot* shot = shots + picks[k];
			views[view_count++] = ( sere_leafpics_frame ){
				shot->x, shot->y, shot->z, shot->rwc, n, (int) shot->frame, shot->frame > 0 ? shot->relative_water : 1.0
			};
		}
		snprintf( title, sizeof( title ), "%s, preset %s: fresh, middle and dry in 3D (oblique) and from above", name,
				  preset ? preset : "default" );
		snprintf( picture, sizeof( picture ), "%s/drying3d.png", out );
		picture_failed =
			picture_failed || sere_leafpics_sheet( picture, title, view_count, views, model.tri, model.triangle_count,
												   (float) params.ground, err, sizeof( err ) ) != 0;
		snprintf( title, sizeof( title ), "%s, preset %s, frame %d", name, preset ? preset : "default",
				  views[view_count - 1].frame );
		snprintf( picture, sizeof( picture ), "%s/leaf3d.png", out );
		picture_failed = picture_failed ||
						 sere_leafpics_view( picture, title, views + view_count - 1, model.tri, model.triangle_count,
											 (float) params.ground, 900, err, sizeof( err ) ) != 0;
	}
	if ( picture_failed && failure[0] == '\0' )
	{
		snprintf( failure, sizeof( failure ), "%s", err );
		fprintf( stderr, "sere run: %s\n", failure );
	}

	/* Summary, Table 1 breakdown in mean ms per frame. */
	char summary_path[4096];
	snprintf( summary_path, sizeof( summary_path ), "%s/summary.json", out );
	sere_atomic_file summary_file;
	FILE* summary = sere_atomic_open( &summary_file, summary_path );
	int summary_error = errno;
	/* How far the run got: "complete", "interrupted" or "error: " and the first failure; frames
	 * completed have all their outputs written. */
	char status_text[4600], status_json[6 * sizeof( status_text )], name_json[6 * sizeof( name )];
	char preset_json[6 * 4096];
	if ( status != SERE_OK )
	{
		snprintf( status_text, sizeof( status_text ), "error: frame %lld: %s", done + 1, sere_status_text( status ) );
	}
	else
	{
		snprintf( status_text, sizeof( status_text ), "%s%s",
				  failure[0] != '\0' ? "error: "
				  : interrupted		 ? "interrupted"
									 : "complete",
				  failure );
	}
	long long completed = stopped && done > 0 ? done - 1 : done;
	double frames_done = done > 0 ? (double) done : 1.0;
	if ( summary != NULL )
	{
		fprintf(
			summary,
			"{\n  \"leaf\": \"%s\",\n  \"preset\": \"%s\",\n  \"status\": \"%s\",\n  \"frames\": %lld,\n"
			"  \"frames_completed\": %lld,\n  \"frames_requested\": %lld,\n"
			"  \"interrupted\": %s,\n  \"threads\": %d,\n  \"particles\": %d,\n  \"springs\": %d,\n"
			"  \"triangles\": %d,\n  \"relative_water\": %.6g,\n  \"relative_area\": %.6g,\n"
			"  \"osmosis_ms\": %.4f,\n  \"dynamics_ms\": %.4f,\n  \"collisions_ms\": %.4f,\n  \"total_ms\": %.4f,\n"
			"  \"pbd_tolerance\": %g,\n  \"pbd_cap\": %d,\n  \"pbd_cap_hits\": %lld,\n  \"pbd_stalls\": %lld,\n"
			"  \"pbd_max_iterations\": %d,\n",
			sere_json_escape( name_json, sizeof( name_json ), name ),
			sere_json_escape( preset_json, sizeof( preset_json ), preset ? preset : "default" ),
			sere_json_escape( status_json, sizeof( status_json ), status_text ), done, completed, frames,
			interrupted ? "true" : "false", bound, model.p.count, model.s.count, model.triangle_count,
			done > 0 ? stats.relative_water : 1.0, curve_area[done > 0 ? done : 0], sum_osmosis / frames_done,
			sum_dynamics / frames_done, sum_collisions / frames_done, sum_total / frames_done, params.strain_tolerance,
			(int) params.max_iterations, cap_hits, stalls, max_pbd_iterations );
		/* the frame rule and what a user looks for, over the whole run (docs/DESIGN.md, measures) */
		fprintf( summary,
				 "  \"pbd_rule\": \"%s\",\n  \"converged_frames\": %lld,\n  \"crossings_max\": %lld,\n"
				 "  \"crossing_frames\": %lld,\n  \"drift_max\": %.6g,\n  \"mass_drift_max\": %.6g,\n"
				 "  \"tilt_max_degrees\": %.4g,\n  \"ground_gap_max\": ",
				 params.compliance > 0.0 ? "xpbd residual" : "paper (max |C/l| < lambda_C or the cap)", converged,
				 (long long) crossings_max, crossing_frames, drift_max, mass_drift_max, tilt_max );
		json_number( summary, gap_max );
		fprintf( summary, ",\n  \"roll_onset\": {\"threshold\": %g, \"tip_frame\": ", ROLL_ONSET );
		json_number( summary, onset_tip >= 0 ? (double) onset_tip : NAN );
		fprintf( summary, ", \"base_frame\": " );
		json_number( summary, onset_base >= 0 ? (double) onset_base : NAN );
		fprintf( summary, "},\n  \"fresh_length\": %.6g,\n", sere_watch_length( watch ) );
		print_shape( summary, "shape_fresh", &shape_fresh, sere_watch_length( watch ) );
		print_shape( summary, "shape_dry", &shape_dry, sere_watch_length( watch ) );
		sere_machine_json( summary, "  ", bound );
		fprintf( summary, ",\n  \"parameters\": {\n" );
		sere_params_print_json( &params, summary, "    " );
		fprintf( summary, "  }\n}\n" );
		if ( sere_atomic_commit( &summary_file ) != 0 && failure[0] == '\0' )
		{
			snprintf( failure, sizeof( failure ), "cannot write %s: %s", summary_path, strerror( errno ) );
			fprintf( stderr, "sere run: %s\n", failure );
		}
	}
	else if ( failure[0] == '\0' )
	{
		snprintf( failure, sizeof( failure ), "cannot write %s: %s", summary_path, strerror( summary_error ) );
		fprintf( stderr, "sere run: %s\n", failure );
	}
	printf( "%s: %lld frames, %d particles, %d springs, %d threads\n", name, done, model.p.count, model.s.count,
			bound );
	printf( "  relative water %.1f%%, leaf area %.1f%% of fresh\n", 100.0 * ( done > 0 ? stats.relative_water : 1.0 ),
			100.0 * curve_area[done > 0 ? done : 0] );
	printf( "  ms per frame: osmotic flow %.3f, dynamics %.3f, collisions %.3f, total %.3f\n",
			sum_osmosis / frames_done, sum_dynamics / frames_done, sum_collisions / frames_done,
			sum_total / frames_done );
	printf( "  frames: %s stop %g, converged in %lld of %lld (cap %d)",
			params.compliance > 0.0 ? "XPBD residual" : "paper |C/l|", params.strain_tolerance, converged, done,
			(int) params.max_iterations );
	if ( params.pbd_stall > 0.0 )
	{
		printf( ", stalled (pbd_stall %g) in %lld", params.pbd_stall, stalls );
	}
	printf( "\n  shape: extent %.2f of fresh length, edge-triangle crossings %lld at most (in %lld frames), "
			"drift %.3f L\n",
			shape_dry.extent / sere_watch_length( watch ), (long long) crossings_max, crossing_frames, drift_max );
	printf( "  pictures: %s/drying3d.png (3D) and %s/drying.png, %s/curves.png\n  frames:   %s/frames (PLY, VTP; open "
			"%s/leaf.pvd in "
			"ParaView)\n  stats:    %s/stats.csv, %s/summary.json\n",
			out, out, out, out, out, out, out );
	for ( int k = 0; k < shot_count; ++k )
	{
		free( shots[k].x ), free( shots[k].y ), free( shots[k].z ), free( shots[k].rwc );
	}
	free( rwc ), free( curve_t ), free( curve_rwc ), free( curve_area );
	sere_pvd_free( &pvd );
	sere_watch_destroy( watch );
	if ( have_veins )
	{
		sere_leaf_free( &veins );
	}
	sere_leaf_destroy( sim );
	sere_model_destroy( &model );
	return status == SERE_OK && failure[0] == '\0' ? ( interrupted ? 130 : 0 ) : 1;
}
