#define _POSIX_C_SOURCE 200809L
#include "cli/cmd_leaf.h"
#include "cli/commands.h"
#include "cli/options.h"
#include "common/io.h"
#include "common/machine.h"
#include "common/topo.h"
#include "common/watch.h"
#include "drying/leaf.h"
#include "read/build.h"
#include "read/leafload.h"
#include "render/leafpics.h"
#include "render/render.h"

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
			"  stats.csv               one row per frame: water per layer, area, max |C/l|, the step's residual,\n"
			"                          the share of its multipliers' forces it leaves unbalanced (step_primal)\n"
			"                          and whether it converged, particles on the ground, edge-triangle crossings,\n"
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
			"  --until-dry       stop at the frame the leaf has dried (Sec. 6), within --frames\n"
			"  --out DIR         output directory (default out/run)\n"
			"  --every K         write a mesh frame every K frames (default: about 24 frames in all)\n"
			"  --points N        triangle-layer points (default 1500; a leaf needs enough for its outline and veins,\n"
			"                    the error names a count that builds); or --particles P --springs S exactly\n"
			"  --threads T       OpenMP threads, bound to cores with hwloc (default: one per core)\n"
			"  --set key=value   override a parameter; keys:\n" );
	sere_params_describe( stdout );
	printf( "Interrupting (Ctrl-C) stops after the current frame and still writes the summary and pictures.\n" );
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
	sere_status failed =
		sere_ply_write( path, p->x, p->y, p->z, n, model->tri, model->triangle_count, NULL, properties, 4 );
	if ( !failed )
	{
		snprintf( path, sizeof( path ), "%s/frames/frame_%05d.vtp", out, frame );
		failed = sere_vtp_write( path, p->x, p->y, p->z, n, model->tri, model->triangle_count, properties, 4 );
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

static sere_status draw_panel( void* user, int index, cairo_t* cr, double x, double y, double w, double h,
							   char* caption, size_t caption_size, char* err, size_t err_size )
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

/* The shape measures of kernels/mesh/measure.h as a JSON object member. */
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

/* What the command line asks for. */
typedef struct run_options
{
	const char* path;
	const char* preset;
	const char* out;
	long long frames, every, points, particles, springs, threads;
	int until_dry;
	sere_sim_params params;
} run_options;

/* SERE_OPTIONS_GO to run, else the exit code: 0 after --help, 2 for bad input (the message is out). */
static int parse_run_options( int argc, char** argv, run_options* o )
{
	*o = ( run_options ){ .out = "out/run", .frames = 400, .points = 1500, .particles = -1, .springs = -1 };
	o->params = sere_sim_params_default();
	sere_option_list sets = { .count = 0 };
	/* in the order of the usage text */
	const sere_option options[] = {
		sere_option_preset( &o->preset ),
		{ "--frames", SERE_OPTION_COUNT, &o->frames, 1, 100000000, NULL },
		{ "--until-dry", SERE_OPTION_FLAG, &o->until_dry, 0, 0, NULL },
		sere_option_out( &o->out ),
		{ "--every", SERE_OPTION_COUNT, &o->every, 1, 100000000, NULL },
		sere_option_points( &o->points ),
		sere_option_particles( &o->particles ),
		sere_option_springs( &o->springs ),
		sere_option_threads( &o->threads ),
		sere_option_sets( &sets ),
	};
	int code = sere_options_read( "run", argc, argv, options, sizeof( options ) / sizeof( options[0] ), "LEAF",
								  &o->path, run_help );
	if ( code != SERE_OPTIONS_GO )
	{
		return code;
	}
	if ( o->path == NULL )
	{
		fprintf( stderr, "sere run: missing LEAF (a .leaf file; see sere run --help)\n" );
		return 2;
	}
	if ( !sere_options_counts_paired( "run", o->particles, o->springs ) )
	{
		return 2;
	}
	if ( !command_params_apply( "run", &o->params, o->preset, &sets ) )
	{
		return 2;
	}
	if ( o->every == 0 )
	{
		o->every = o->frames / 24 > 0 ? o->frames / 24 : 1;
	}
	return SERE_OPTIONS_GO;
}

enum
{
	sheet_panels = 12, /* panels of the contact sheet drying.png */
};

/* The first frames whose tip and base sections have rolled by this much: which end rolls first. */
static const double kRollOnset = 0.5;

/* One run: the leaf, its simulation and everything measured and kept along the way. */
typedef struct run_state
{
	const run_options* o;
	int bound; /* threads */
	char name[128];
	sere_leaf_source leaf; /* the file, kept for its veins (the measures along and across them) */
	int have_leaf;
	sere_model model;
	int have_model;
	sere_leaf_sim* sim;
	sere_shape shape_fresh, shape_dry;
	sere_watch* watch;
	sere_watch_frame watched;
	/* over the run */
	long long done, converged, crossing_frames, cap_hits, stalls, onset_tip, onset_base;
	int64_t crossings_max;
	double step_primal_max; /* the largest step_primal of the run (NaN: never measured) */
	int32_t max_pbd_iterations;
	double drift_max, mass_drift_max, gap_max, tilt_max;
	double sum_osmosis, sum_dynamics, sum_collisions, sum_total;
	sere_leaf_stats stats;
	sere_status status; /* the simulation's, SERE_OK unless a step failed */
	/* outputs */
	float* rwc;
	snapshot shots[sheet_panels];
	int shot_count;
	long long shot_every;
	double *curve_t, *curve_rwc, *curve_area;
	double area0;
	sere_pvd_series pvd; /* the mesh frames written, for leaf.pvd */
	sere_atomic_file csv_file;
	FILE* csv;
	char csv_path[4096];
	char failure[4400]; /* the first output error; the run stops there */
} run_state;

/* The shape measures' input for the leaf as it is now. */
static sere_shape_input run_shape_input( const run_state* r )
{
	sere_shape_input in = sere_leaf_shape_input( &r->model, sere_params_decimal( r->o->params.leaf.ground ) );
	in.veins = &r->leaf.file.shape;
	in.threads = r->bound;
	return in;
}

/* Reads and builds the leaf, prepares the output directory, the simulation, the fresh measures
 * and Sec. 3.1's initial shaping. 0, or 1 after the message. */
static int run_open_leaf( run_state* r )
{
	const run_options* o = r->o;
	char err[1024];
	if ( sere_leaf_source_load( o->path, &r->leaf, err, sizeof( err ) ) != 0 )
	{
		fprintf( stderr, "sere run: %s\n", err );
		return 1;
	}
	r->have_leaf = 1;
	sere_build_report report;
	if ( sere_harness_build_leaf( &r->leaf, o->path, o->particles, o->springs, o->points, &o->params, &r->model,
								  &report, r->name, sizeof( r->name ), err, sizeof( err ) ) != 0 )
	{
		fprintf( stderr, "sere run: %s\n", err );
		return 1;
	}
	r->have_model = 1;
	char frames_dir[4096];
	snprintf( frames_dir, sizeof( frames_dir ), "%s/frames", o->out );
	if ( sere_dir_create( frames_dir ) != 0 )
	{
		fprintf( stderr, "sere run: cannot create %s: %s\n", frames_dir, strerror( errno ) );
		return 1;
	}
	static const char* const outputs[] = { "stats.csv",	 "summary.json", "leaf.pvd",  "drying.png",
										   "curves.png", "drying3d.png", "leaf3d.png" };
	if ( sere_outputs_check( o->out, outputs, sizeof( outputs ) / sizeof( outputs[0] ), err, sizeof( err ) ) != 0 )
	{
		fprintf( stderr, "sere run: %s\n", err );
		return 1;
	}
	remove_old_frames( frames_dir );
	if ( o->params.face_down )
	{
		sere_model_mirror_z( &r->model );
	}
	sere_model_rest_on( &r->model, o->params.leaf.ground );
	sere_status status = sere_leaf_create( &r->model, &r->sim );
	status = status == SERE_OK ? sere_leaf_set_threads( r->sim, r->bound ) : status;
	if ( status != SERE_OK )
	{
		fprintf( stderr, "sere run: %s\n", sere_status_text( status ) );
		return 1;
	}
	/* the fresh shape, and a watch on crossings, drift, the ground and turning over */
	sere_shape_input shape_input = run_shape_input( r );
	status = sere_shape_measure( &shape_input, &r->shape_fresh );
	if ( status == SERE_OK )
	{
		status = sere_watch_create( &r->model, sere_params_decimal( o->params.leaf.ground ), r->bound, &r->watch );
	}
	if ( status != SERE_OK )
	{
		fprintf( stderr, "sere run: cannot measure the fresh leaf: %s\n", sere_status_text( status ) );
		return 1;
	}
	r->shape_dry = r->shape_fresh;
	if ( o->params.crease != 0.0f || o->params.curl != 0.0f )
	{
		/* Sec. 3.1: creases along the veins and a curled blade before drying starts. */
		sere_pbd_params shaping = o->params.leaf.pbd;
		shaping.max_iterations = 2000;
		status = sere_leaf_shape_initial( r->sim, o->params.crease, o->params.curl, &shaping );
		if ( status != SERE_OK )
		{
			fprintf( stderr, "sere run: initial shaping: %s\n", sere_status_text( status ) );
			return 1;
		}
	}
	return 0;
}

/* The per-frame buffers and stats.csv, opened with its header. 0, or 1 after the message. */
static int run_open_outputs( run_state* r )
{
	const long long frames = r->o->frames;
	r->rwc = malloc( sizeof( float ) * (size_t) r->model.p.capacity );
	r->curve_t = malloc( sizeof( double ) * (size_t) ( frames + 1 ) );
	r->curve_rwc = malloc( sizeof( double ) * (size_t) ( frames + 1 ) );
	r->curve_area = malloc( sizeof( double ) * (size_t) ( frames + 1 ) );
	if ( !r->rwc || !r->curve_t || !r->curve_rwc || !r->curve_area )
	{
		fprintf( stderr, "sere run: out of memory\n" );
		return 1;
	}
	snprintf( r->csv_path, sizeof( r->csv_path ), "%s/stats.csv", r->o->out );
	r->csv = sere_atomic_open( &r->csv_file, r->csv_path );
	if ( r->csv == NULL )
	{
		fprintf( stderr, "sere run: cannot write %s: %s\n", r->csv_path, strerror( errno ) );
		return 1;
	}
	fprintf( r->csv,
			 "frame,time,water_t,water_v,relative_water,area,relative_area,max_strain,residual,step_primal,converged,"
			 "grounded,crossings,drift,mass_drift,ground_gap,normal_z,tilt,roll_tip,roll_base,cg_iterations_t,"
			 "cg_iterations_v,pbd_iterations,pbd_hit_cap,pbd_stalled,contacts,edge_contacts,unresolved,"
			 "thickness,desiccated,osmosis_ms,dynamics_ms,collisions_ms,total_ms\n" );
	return 0;
}

/* Reports an output error (the first one ends the run). */
static void run_fail_output( run_state* r, const sere_progress* progress )
{
	fprintf( stderr, "%ssere run: %s\n", progress->active ? "\n" : "", r->failure );
}

/* One frame of Algorithm 1, its measures, its stats.csv line and (every --every frames) its
 * mesh. 0 to go on, -1 to stop (the message is out). */
static int run_step( run_state* r, long long frame, const sere_progress* progress )
{
	const run_options* o = r->o;
	sere_leaf_stats next;
	r->status = sere_leaf_step( r->sim, &o->params.leaf, &next );
	if ( r->status != SERE_OK )
	{
		char why[256];
		command_step_error( &o->params, r->status, why, sizeof( why ) );
		fprintf( stderr, "\nsere run: frame %lld: %s\n", frame, why );
		return -1;
	}
	const sere_leaf_stats* s = &r->stats;
	r->stats = next;
	r->done = frame;
	r->sum_osmosis += s->osmosis_ms, r->sum_dynamics += s->dynamics_ms;
	r->sum_collisions += s->collisions_ms, r->sum_total += s->total_ms;
	r->cap_hits += s->pbd_hit_cap;
	r->stalls += s->pbd_stalled;
	r->max_pbd_iterations = s->pbd_iterations > r->max_pbd_iterations ? s->pbd_iterations : r->max_pbd_iterations;
	sere_status status = sere_watch_step( r->watch, &r->model, &r->watched );
	if ( status != SERE_OK )
	{
		fprintf( stderr, "\nsere run: frame %lld: cannot measure: %s\n", frame, sere_status_text( status ) );
		return -1;
	}
	const sere_watch_frame* w = &r->watched;
	r->converged += s->pbd_converged;
	r->step_primal_max = fmax( r->step_primal_max, s->step_primal );
	r->crossing_frames += w->crossings > 0;
	r->crossings_max = w->crossings > r->crossings_max ? w->crossings : r->crossings_max;
	r->drift_max = fmax( r->drift_max, w->drift );
	r->mass_drift_max = fmax( r->mass_drift_max, w->mass_drift );
	r->gap_max = fmax( r->gap_max, w->ground_gap );
	r->tilt_max = fmax( r->tilt_max, w->tilt_degrees );
	r->onset_tip = r->onset_tip < 0 && fabs( w->roll_tip ) >= kRollOnset ? frame : r->onset_tip;
	r->onset_base = r->onset_base < 0 && fabs( w->roll_base ) >= kRollOnset ? frame : r->onset_base;
	double area = leaf_area( &r->model );
	r->curve_t[frame] = frame * sere_params_decimal( o->params.leaf.dt );
	r->curve_rwc[frame] = s->relative_water;
	r->curve_area[frame] = area / r->area0;
	fprintf( r->csv,
			 "%lld,%.6g,%.9g,%.9g,%.6g,%.9g,%.6g,%.6g,%.6g,%.4g,%d,%d,%lld,%.6g,%.6g,%.6g,%.6g,%.4g,%.4g,%.4g,"
			 "%d,%d,%d,%d,%d,%d,%d,%d,%.6g,%d,%.4f,%.4f,%.4f,%.4f\n",
			 frame, frame * sere_params_decimal( o->params.leaf.dt ), s->water_t, s->water_v, s->relative_water, area,
			 area / r->area0, s->max_strain, s->residual, s->step_primal, s->pbd_converged, s->grounded,
			 (long long) w->crossings, w->drift, w->mass_drift, w->ground_gap, w->normal_z, w->tilt_degrees,
			 w->roll_tip, w->roll_base, s->cg_iterations_t, s->cg_iterations_v, s->pbd_iterations, s->pbd_hit_cap,
			 s->pbd_stalled, s->contacts, s->edge_contacts, s->unresolved, s->collision_thickness, s->desiccated,
			 s->osmosis_ms, s->dynamics_ms, s->collisions_ms, s->total_ms );
	if ( fflush( r->csv ) != 0 )
	{
		snprintf( r->failure, sizeof( r->failure ), "cannot write %s: %s", r->csv_path, strerror( errno ) );
		run_fail_output( r, progress );
		return -1;
	}
	sere_leaf_relative_water( r->sim, r->rwc );
	if ( ( frame % o->every == 0 || frame == o->frames ) &&
		 write_frame( o->out, (int) frame, frame * sere_params_decimal( o->params.leaf.dt ), &r->model, r->rwc, &r->pvd,
					  r->failure, sizeof( r->failure ) ) != 0 )
	{
		run_fail_output( r, progress );
		return -1;
	}
	return 0;
}

static void snapshot_free( snapshot* s )
{
	free( s->x ), free( s->y ), free( s->z ), free( s->rwc );
}

/* Keeps at most sheet_panels evenly spaced panels for the contact sheet whatever the run's
 * length: when full, drops every other one and takes them half as often. */
static void run_keep_shot( run_state* r, long long frame, int last )
{
	if ( frame % r->shot_every != 0 && !last )
	{
		return;
	}
	if ( r->shot_count == sheet_panels )
	{
		for ( int k = 1; k < sheet_panels; k += 2 )
		{
			snapshot_free( r->shots + k );
		}
		for ( int k = 0; k < sheet_panels / 2; ++k )
		{
			r->shots[k] = r->shots[2 * k];
		}
		r->shot_count = sheet_panels / 2;
		r->shot_every *= 2;
	}
	if ( frame % r->shot_every != 0 && !last )
	{
		return;
	}
	/* The final state replaces a panel less than half a spacing before it, so the sheet never
	 * ends on two near-identical pictures. */
	if ( last && r->shot_count > 1 && 2 * ( frame - r->shots[r->shot_count - 1].frame ) < r->shot_every )
	{
		snapshot_free( r->shots + --r->shot_count );
	}
	snapshot* s = r->shots + r->shot_count++;
	s->frame = frame;
	s->relative_water = r->stats.relative_water;
	size_t bytes = sizeof( float ) * (size_t) r->model.triangle_particles;
	s->x = malloc( bytes ), s->y = malloc( bytes ), s->z = malloc( bytes ), s->rwc = malloc( bytes );
	memcpy( s->x, r->model.p.x, bytes ), memcpy( s->y, r->model.p.y, bytes ), memcpy( s->z, r->model.p.z, bytes );
	memcpy( s->rwc, r->rwc, bytes );
	snprintf( s->caption, sizeof( s->caption ), "frame %lld, water %.0f%%", frame,
			  100.0 * ( frame > 0 ? r->stats.relative_water : 1.0 ) );
}

/* Frame 0, then Algorithm 1 frame by frame until --frames, the leaf dries (--until-dry), an
 * interrupt or the first error; then the dry shape's measures. Returns 1 when an output error
 * ended the frames (the last frame then lacks some of its outputs), else 0. */
static int run_frames( run_state* r )
{
	const run_options* o = r->o;
	signal( SIGINT, on_signal );
	signal( SIGTERM, on_signal );
	signal( SIGXFSZ, SIG_IGN ); /* past a file-size limit a write fails (EFBIG) and is reported */
	r->area0 = leaf_area( &r->model );
	sere_leaf_relative_water( r->sim, r->rwc );
	if ( write_frame( o->out, 0, 0.0, &r->model, r->rwc, &r->pvd, r->failure, sizeof( r->failure ) ) != 0 )
	{
		fprintf( stderr, "sere run: %s\n", r->failure );
	}
	r->curve_t[0] = 0.0, r->curve_rwc[0] = 1.0, r->curve_area[0] = 1.0;
	sere_progress progress;
	sere_progress_begin( &progress, "drying", o->frames );
	for ( long long frame = 0; frame <= o->frames && !interrupted && r->failure[0] == '\0'; ++frame )
	{
		if ( frame > 0 && run_step( r, frame, &progress ) != 0 )
		{
			break;
		}
		int dry = o->until_dry && r->stats.desiccated;
		run_keep_shot( r, frame, frame == o->frames || dry );
		sere_progress_update( &progress, frame );
		if ( dry )
		{
			if ( frame % o->every != 0 &&
				 write_frame( o->out, (int) frame, frame * sere_params_decimal( o->params.leaf.dt ), &r->model, r->rwc,
							  &r->pvd, r->failure, sizeof( r->failure ) ) != 0 )
			{
				run_fail_output( r, &progress );
			}
			break;
		}
	}
	sere_progress_end( &progress );
	int stopped = r->failure[0] != '\0'; /* an output error ended the loop */
	if ( sere_atomic_commit( &r->csv_file ) != 0 && !stopped )
	{
		snprintf( r->failure, sizeof( r->failure ), "cannot write %s: %s", r->csv_path, strerror( errno ) );
		fprintf( stderr, "sere run: %s\n", r->failure );
	}
	r->csv = NULL;
	sere_shape_input shape_input = run_shape_input( r );
	if ( r->done > 0 && sere_shape_measure( &shape_input, &r->shape_dry ) != SERE_OK )
	{
		r->shape_dry = r->shape_fresh;
	}
	return stopped;
}

/* drying.png (contact sheet), curves.png, and the shape in 3D (Fig. 17 (a)-(b)): fresh, middle
 * and dry from an oblique camera with the ground and the shadow, above the top view
 * (drying3d.png); then the dry leaf alone, larger (leaf3d.png). */
static void run_pictures( run_state* r )
{
	const run_options* o = r->o;
	const char* preset = o->preset ? o->preset : "default";
	const int32_t n = r->model.triangle_particles;
	char picture[4096], title[256], err[1024] = "";
	sheet_context sheet_user = { r->shots, r->model.tri, r->model.triangle_count,
								 n,		   NULL,		 { -35.0, 50.0, { 0, 0, 0 }, 0.0, 8.0 } };
	sheet_user.rgb = malloc( sizeof( float ) * 3 * (size_t) n );
	snprintf( title, sizeof( title ), "%s, preset %s: drying colored by relative water content", r->name, preset );
	snprintf( picture, sizeof( picture ), "%s/drying.png", o->out );
	sere_render_sheet sheet = { title, 4, r->shot_count, 320, 300, draw_panel, &sheet_user };
	int failed = sheet_user.rgb == NULL || sere_render_contact_sheet( picture, &sheet, err, sizeof( err ) ) != 0;
	free( sheet_user.rgb );
	sere_render_series curves[2] = {
		{ "relative water content", r->curve_t, r->curve_rwc, (int32_t) r->done + 1, { 0.0f, 0.45f, 0.70f }, 0 },
		{ "relative leaf area", r->curve_t, r->curve_area, (int32_t) r->done + 1, { 0.55f, 0.36f, 0.17f }, 0 }
	};
	snprintf( title, sizeof( title ), "%s, preset %s: relative water content and leaf area", r->name, preset );
	sere_render_axes axes = { title, "time", "fraction of initial", 1, 0.0, 1.05 };
	snprintf( picture, sizeof( picture ), "%s/curves.png", o->out );
	failed = failed || sere_render_plot( picture, 800, 480, &axes, curves, 2, err, sizeof( err ) ) != 0;
	if ( r->shot_count > 0 )
	{
		const int picks[3] = { 0, r->shot_count / 2, r->shot_count - 1 };
		sere_leafpics_frame views[3];
		int view_count = 0;
		for ( int k = 0; k < 3; ++k )
		{
			if ( k > 0 && picks[k] == picks[k - 1] )
			{
				continue;
			}
			const snapshot* shot = r->shots + picks[k];
			views[view_count++] = ( sere_leafpics_frame ){
				shot->x, shot->y, shot->z, shot->rwc, n, (int) shot->frame, shot->frame > 0 ? shot->relative_water : 1.0
			};
		}
		const float ground = o->params.leaf.ground;
		snprintf( title, sizeof( title ), "%s, preset %s: fresh, middle and dry in 3D (oblique) and from above",
				  r->name, preset );
		snprintf( picture, sizeof( picture ), "%s/drying3d.png", o->out );
		failed = failed || sere_leafpics_sheet( picture, title, view_count, views, r->model.tri,
												r->model.triangle_count, ground, err, sizeof( err ) ) != 0;
		snprintf( title, sizeof( title ), "%s, preset %s, frame %d", r->name, preset, views[view_count - 1].frame );
		snprintf( picture, sizeof( picture ), "%s/leaf3d.png", o->out );
		failed = failed || sere_leafpics_view( picture, title, views + view_count - 1, r->model.tri,
											   r->model.triangle_count, ground, 900, err, sizeof( err ) ) != 0;
	}
	if ( failed && r->failure[0] == '\0' )
	{
		snprintf( r->failure, sizeof( r->failure ), "%s", err );
		fprintf( stderr, "sere run: %s\n", r->failure );
	}
}

/* How far the run got: "complete", "interrupted" or "error: " and the first failure; frames
 * completed have all their outputs written. */
static void run_status_text( const run_state* r, char* text, size_t size )
{
	if ( r->status != SERE_OK )
	{
		char why[256];
		command_step_error( &r->o->params, r->status, why, sizeof( why ) );
		snprintf( text, size, "error: frame %lld: %s", r->done + 1, why );
	}
	else
	{
		snprintf( text, size, "%s%s",
				  r->failure[0] != '\0' ? "error: "
				  : interrupted			? "interrupted"
										: "complete",
				  r->failure );
	}
}

/* summary.json's members, Table 1's breakdown in mean ms per frame among them. */
static void run_summary_members( const run_state* r, FILE* summary, long long completed )
{
	const run_options* o = r->o;
	const sere_sim_params* params = &o->params;
	char status_text[4600], status_json[6 * sizeof( status_text )], name_json[6 * sizeof( r->name )];
	char preset_json[6 * 4096];
	run_status_text( r, status_text, sizeof( status_text ) );
	double frames_done = r->done > 0 ? (double) r->done : 1.0;
	fprintf( summary,
			 "{\n  \"leaf\": \"%s\",\n  \"preset\": \"%s\",\n  \"status\": \"%s\",\n  \"frames\": %lld,\n"
			 "  \"frames_completed\": %lld,\n  \"frames_requested\": %lld,\n"
			 "  \"interrupted\": %s,\n  \"threads\": %d,\n  \"particles\": %d,\n  \"springs\": %d,\n"
			 "  \"triangles\": %d,\n  \"relative_water\": %.6g,\n  \"relative_area\": %.6g,\n"
			 "  \"osmosis_ms\": %.4f,\n  \"dynamics_ms\": %.4f,\n  \"collisions_ms\": %.4f,\n  \"total_ms\": %.4f,\n"
			 "  \"pbd_tolerance\": %g,\n  \"pbd_cap\": %d,\n  \"pbd_cap_hits\": %lld,\n  \"pbd_stalls\": %lld,\n"
			 "  \"pbd_max_iterations\": %d,\n",
			 sere_json_escape( name_json, sizeof( name_json ), r->name ),
			 sere_json_escape( preset_json, sizeof( preset_json ), o->preset ? o->preset : "default" ),
			 sere_json_escape( status_json, sizeof( status_json ), status_text ), r->done, completed, o->frames,
			 interrupted ? "true" : "false", r->bound, r->model.p.count, r->model.s.count, r->model.triangle_count,
			 r->done > 0 ? r->stats.relative_water : 1.0, r->curve_area[r->done > 0 ? r->done : 0],
			 r->sum_osmosis / frames_done, r->sum_dynamics / frames_done, r->sum_collisions / frames_done,
			 r->sum_total / frames_done, params->leaf.pbd.tolerance, params->leaf.pbd.max_iterations, r->cap_hits,
			 r->stalls, r->max_pbd_iterations );
	/* the frame rule and what a user looks for, over the whole run (docs/DESIGN.md, measures) */
	fprintf( summary,
			 "  \"pbd_rule\": \"%s\",\n  \"converged_frames\": %lld,\n  \"crossings_max\": %lld,\n"
			 "  \"crossing_frames\": %lld,\n  \"drift_max\": %.6g,\n  \"mass_drift_max\": %.6g,\n"
			 "  \"tilt_max_degrees\": %.4g,\n  \"ground_gap_max\": ",
			 params->leaf.pbd.compliance == 0.0f ? "paper (max |C/l| < lambda_C or the cap)"
			 : params->leaf.descent				 ? "descent (largest move < descent_tolerance of a spring)"
												 : "xpbd residual",
			 r->converged, (long long) r->crossings_max, r->crossing_frames, r->drift_max, r->mass_drift_max,
			 r->tilt_max );
	json_number( summary, r->gap_max );
	/* the share of the springs' forces the step leaves unbalanced (docs/DESIGN.md §8) */
	fprintf( summary, ",\n  \"step_primal_last\": " );
	json_number( summary, r->done > 0 ? r->stats.step_primal : NAN );
	fprintf( summary, ",\n  \"step_primal_max\": " );
	json_number( summary, r->step_primal_max );
	fprintf( summary, ",\n  \"roll_onset\": {\"threshold\": %g, \"tip_frame\": ", kRollOnset );
	json_number( summary, r->onset_tip >= 0 ? (double) r->onset_tip : NAN );
	fprintf( summary, ", \"base_frame\": " );
	json_number( summary, r->onset_base >= 0 ? (double) r->onset_base : NAN );
	fprintf( summary, "},\n  \"fresh_length\": %.6g,\n", sere_watch_length( r->watch ) );
	print_shape( summary, "shape_fresh", &r->shape_fresh, sere_watch_length( r->watch ) );
	print_shape( summary, "shape_dry", &r->shape_dry, sere_watch_length( r->watch ) );
	sere_machine_json( summary, "  ", r->bound );
	fprintf( summary, ",\n  \"parameters\": {\n" );
	sere_params_print_json( params, summary, "    " );
	fprintf( summary, "  }\n}\n" );
}

/* summary.json, written atomically. */
static void run_write_summary( run_state* r, long long completed )
{
	char summary_path[4096];
	snprintf( summary_path, sizeof( summary_path ), "%s/summary.json", r->o->out );
	sere_atomic_file summary_file;
	FILE* summary = sere_atomic_open( &summary_file, summary_path );
	int summary_error = errno;
	if ( summary != NULL )
	{
		run_summary_members( r, summary, completed );
		if ( sere_atomic_commit( &summary_file ) != 0 && r->failure[0] == '\0' )
		{
			snprintf( r->failure, sizeof( r->failure ), "cannot write %s: %s", summary_path, strerror( errno ) );
			fprintf( stderr, "sere run: %s\n", r->failure );
		}
	}
	else if ( r->failure[0] == '\0' )
	{
		snprintf( r->failure, sizeof( r->failure ), "cannot write %s: %s", summary_path, strerror( summary_error ) );
		fprintf( stderr, "sere run: %s\n", r->failure );
	}
}

/* The closing report on stdout. */
static void run_print( const run_state* r )
{
	const run_options* o = r->o;
	const char* out = o->out;
	double frames_done = r->done > 0 ? (double) r->done : 1.0;
	printf( "%s: %lld frames, %d particles, %d springs, %d threads\n", r->name, r->done, r->model.p.count,
			r->model.s.count, r->bound );
	printf( "  relative water %.1f%%, leaf area %.1f%% of fresh\n",
			100.0 * ( r->done > 0 ? r->stats.relative_water : 1.0 ), 100.0 * r->curve_area[r->done > 0 ? r->done : 0] );
	printf( "  ms per frame: osmotic flow %.3f, dynamics %.3f, collisions %.3f, total %.3f\n",
			r->sum_osmosis / frames_done, r->sum_dynamics / frames_done, r->sum_collisions / frames_done,
			r->sum_total / frames_done );
	printf( "  frames: %s stop %g, converged in %lld of %lld (cap %d)",
			o->params.leaf.pbd.compliance == 0.0f ? "paper |C/l|"
			: o->params.leaf.descent			  ? "descent (moves below descent_tolerance of a spring)"
												  : "XPBD residual",
			o->params.leaf.descent && o->params.leaf.pbd.compliance > 0.0f ? o->params.leaf.descent_tolerance
																		   : o->params.leaf.pbd.tolerance,
			r->converged, r->done, o->params.leaf.pbd.max_iterations );
	if ( o->params.leaf.pbd.stall > 0.0f )
	{
		printf( ", stalled (pbd_stall %g) in %lld", o->params.leaf.pbd.stall, r->stalls );
	}
	printf( "\n  shape: extent %.2f of fresh length, edge-triangle crossings %lld at most (in %lld frames), "
			"drift %.3f L\n",
			r->shape_dry.extent / sere_watch_length( r->watch ), (long long) r->crossings_max, r->crossing_frames,
			r->drift_max );
	printf( "  pictures: %s/drying3d.png (3D) and %s/drying.png, %s/curves.png\n  frames:   %s/frames (PLY, VTP; open "
			"%s/leaf.pvd in ParaView)\n  stats:    %s/stats.csv, %s/summary.json\n",
			out, out, out, out, out, out, out );
}

static void run_close( run_state* r )
{
	if ( r->csv != NULL )
	{
		sere_atomic_abort( &r->csv_file );
	}
	for ( int k = 0; k < r->shot_count; ++k )
	{
		snapshot_free( r->shots + k );
	}
	free( r->rwc ), free( r->curve_t ), free( r->curve_rwc ), free( r->curve_area );
	sere_pvd_destroy( &r->pvd );
	sere_watch_destroy( r->watch );
	sere_leaf_destroy( r->sim );
	if ( r->have_model )
	{
		sere_model_destroy( &r->model );
	}
	if ( r->have_leaf )
	{
		sere_leaf_source_destroy( &r->leaf );
	}
}

int sere_cmd_run( int argc, char** argv )
{
	run_options o;
	int parsed = parse_run_options( argc, argv, &o );
	if ( parsed != SERE_OPTIONS_GO )
	{
		return parsed;
	}
	run_state r = {
		.o = &o, .onset_tip = -1, .onset_base = -1, .gap_max = -INFINITY, .step_primal_max = NAN, .shot_every = 1
	};
	r.watched = ( sere_watch_frame ){ 0, 0.0, 0.0, NAN, 1.0, 0.0, NAN, NAN };
	r.bound = sere_topo_bind( (int) o.threads, NULL );
	if ( run_open_leaf( &r ) != 0 || run_open_outputs( &r ) != 0 )
	{
		run_close( &r );
		return 1;
	}
	int stopped = run_frames( &r );
	long long completed = stopped && r.done > 0 ? r.done - 1 : r.done;
	run_pictures( &r );
	run_write_summary( &r, completed );
	run_print( &r );
	int code = r.status == SERE_OK && r.failure[0] == '\0' ? ( interrupted ? 130 : 0 ) : 1;
	run_close( &r );
	return code;
}
