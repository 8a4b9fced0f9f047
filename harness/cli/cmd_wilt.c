/* sere wilt — venation skeleton-based wilting of a leaf or a plant (seed 003: Lu, Zhao, Guo 2009):
 * skeleton file or parametric leaf → blade mesh → banding → frames of wilting, written as PLY, VTK
 * and PNG. */
#define _POSIX_C_SOURCE 200809L
#include "cli/cmd_wilt_shared.h"
#include "cli/commands.h"
#include "cli/options.h"
#include "common/io.h"
#include "common/params.h"
#include "common/topo.h"
#include "mesh/subdivide.h"
#include "wilt/skeleton.h"

#include <errno.h>
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void wilt_help( void )
{
	printf(
		"usage: sere wilt [SKELETON] [options]\n\n"
		"Wilts a leaf, or a plant of leaves on a stem, with the venation skeleton method of Lu, Zhao & Guo\n"
		"(2009): the blade is meshed by constrained Delaunay triangulation and 1-to-4 subdivision, every vertex\n"
		"is banded to its nearest skeleton joint, and each joint turns its segment toward the downward vector\n"
		"with its children following, tips first; lower leaves start before upper ones.\n\n"
		"SKELETON is a skeleton file (a path, or a name in data/skeletons such as cucumber or watermelon); without\n"
		"it the parametric leaf of Sec. 4.1 is used.\n\n"
		"leaf:\n"
		"  --length L --width W --features K  parametric leaf: midvein length, blade width, feature points per\n"
		"                                     curve (default 10, 6, 9)\n"
		"  --spacing H       sampling interval of outline, midvein and interior (default leaf length / 25)\n"
		"  --subdivide K     1-to-4 subdivision passes (default 1)\n"
		"  --min-edge E      subdivision never makes edges shorter than E (default 0: cut every edge)\n"
		"venation (generated when the file has no 'vein' blocks):\n"
		"  --mid-segments N  joints along the midvein (default 20)\n"
		"  --veins N         secondary veins (default 8)\n"
		"  --vein-segments N joints along each secondary vein (default 8)\n"
		"  --vein-angle DEG  angle between secondary veins and the midvein (default 45)\n"
		"  --mid-bend DEG    total turn of the midvein at full wilting (default 80)\n"
		"  --vein-bend DEG   total turn of each secondary vein (default 50)\n"
		"wilting (Sec. 6):\n"
		"  --droop D         maximal drooped distance of any joint below its rest height (default: none)\n"
		"  --min-angle DEG   minimal included angle between adjacent segments of a vein (default 120)\n"
		"  --spread S        tip-to-base onset spread within a leaf, in [0, 1) (default 0.5)\n"
		"  --no-pierce       skip the piercing check (faster; the mesh may then pass through itself)\n"
		"plant (Sec. 7):\n"
		"  --leaves N        leaves up the stem, 137.5 degrees apart (default 1)\n"
		"  --stagger S       wilting onset of each leaf after the one below, in units of t (default 0.25)\n"
		"  --internode H     stem length between leaves (default 0.3 x leaf length)\n"
		"  --elevation DEG   rest angle of each midvein above horizontal (default 35)\n"
		"run:\n"
		"  --frames F        frames from t = 0 (default 40)\n"
		"  --speed S         increase of t per frame (default: the top leaf reaches t = 1 on the last frame)\n"
		"  --out DIR         write frame_NNNN.ply, frame_NNNN.vtp + wilt.pvd and frame_NNNN.png to DIR\n"
		"  --format LIST     comma-separated subset of ply,vtp,png (default ply,vtp,png)\n"
		"  --every K         write every K-th frame (the last frame always) (default 1)\n"
		"  --size WxH        picture size in pixels (default 800x600)\n"
		"  --view AZ,EL      picture view direction, degrees (default -70,25)\n"
		"  --threads T       OpenMP threads, 0 = one per core (default 0)\n"
		"  --json            print the summary as one JSON object\n\n"
		"Skeleton files are text: '#' starts a comment; keywords 'name NAME', 'left', 'right', 'midvein' and\n"
		"'vein PARENT SEGMENTS BEND_DEG' each start a block followed by 'x y' lines (leaf coordinates: base at\n"
		"the origin, midvein toward +x). left/right/midvein are the leaf skeleton's feature points from base to\n"
		"tip; each vein is a polyline, vein 0 the midvein with parent -1 (no points: it follows the midvein).\n" );
}

/* ------------------------------------------------------------------------------------------- */
/* Option parsing: one clear line and exit status 2 on a bad value. */

static int parse_pair( const char* option, const char* text, char separator, double lo, double hi, double* a,
					   double* b )
{
	char* end;
	*a = strtod( text, &end );
	if ( end != text && *end == separator )
	{
		const char* second = end + 1;
		*b = strtod( second, &end );
		if ( end != second && *end == '\0' && isfinite( *a ) && isfinite( *b ) && *a >= lo && *a <= hi && *b >= lo &&
			 *b <= hi )
		{
			return 0;
		}
	}
	fprintf( stderr, "sere wilt: %s takes two numbers 'A%cB' from %g to %g, not '%s'\n", option, separator, lo, hi,
			 text );
	return -1;
}

/* ------------------------------------------------------------------------------------------- */

typedef struct wilt_options
{
	const char* skeleton;
	double length, width;
	long long features;
	double spacing; /* 0: length / 25 */
	long long subdivide;
	double min_edge;
	sere_venation_params venation;
	sere_wilt_params wilt;
	long long leaves;
	double stagger, internode, elevation;
	long long frames;
	double speed; /* < 0: derived */
	const char* out;
	int ply, vtp, png;
	long long every;
	double size[2], view[2];
	long long threads;
	int json;
} wilt_options;

static int parse_format( const char* text, wilt_options* o )
{
	o->ply = o->vtp = o->png = 0;
	char copy[256];
	snprintf( copy, sizeof( copy ), "%s", text );
	char* save = NULL;
	int any = 0;
	for ( char* word = strtok_r( copy, ",", &save ); word != NULL; word = strtok_r( NULL, ",", &save ) )
	{
		if ( strcmp( word, "ply" ) == 0 )
		{
			o->ply = 1;
		}
		else if ( strcmp( word, "vtp" ) == 0 )
		{
			o->vtp = 1;
		}
		else if ( strcmp( word, "png" ) == 0 )
		{
			o->png = 1;
		}
		else
		{
			fprintf( stderr, "sere wilt: --format takes a comma-separated subset of ply,vtp,png, not '%s'\n", text );
			return -1;
		}
		any = 1;
	}
	if ( !any )
	{
		fprintf( stderr, "sere wilt: --format takes a comma-separated subset of ply,vtp,png, not '%s'\n", text );
		return -1;
	}
	return 0;
}

static void wilt_defaults( wilt_options* o )
{
	memset( o, 0, sizeof( *o ) );
	o->length = 10.0;
	o->width = 6.0;
	o->features = 9;
	o->subdivide = 1;
	o->venation = sere_venation_params_default();
	o->wilt = sere_wilt_params_default();
	o->leaves = 1;
	o->stagger = 0.25;
	o->internode = -1.0;
	o->elevation = 35.0;
	o->frames = 40;
	o->speed = -1.0;
	o->ply = o->vtp = o->png = 1;
	o->every = 1;
	o->size[0] = 800;
	o->size[1] = 600;
	o->view[0] = -70.0;
	o->view[1] = 25.0;
}

/* SERE_OPTIONS_GO to run, else the exit code: 0 after --help, 2 on a bad option. */
static int parse_options( int argc, char** argv, wilt_options* o )
{
	wilt_defaults( o );
	/* options stored as given, then turned into the kernels' units below (NAN, -1: not given) */
	long long mid_segments = -1, veins = -1, vein_segments = -1;
	double vein_angle = NAN, mid_bend = NAN, vein_bend = NAN, droop = NAN, min_angle = NAN, spread = NAN;
	const char *format = NULL, *size = NULL, *view = NULL;
	int no_pierce = 0;
	const sere_option options[] = {
		{ "--length", SERE_OPTION_REAL, &o->length, 1e-6, 1e6, NULL },
		{ "--width", SERE_OPTION_REAL, &o->width, 1e-6, 1e6, NULL },
		{ "--features", SERE_OPTION_COUNT, &o->features, 3, 10000, NULL },
		{ "--spacing", SERE_OPTION_REAL, &o->spacing, 1e-9, 1e6, NULL },
		{ "--subdivide", SERE_OPTION_COUNT, &o->subdivide, 0, 8, NULL },
		{ "--min-edge", SERE_OPTION_REAL, &o->min_edge, 0.0, 1e6, NULL },
		{ "--mid-segments", SERE_OPTION_COUNT, &mid_segments, 1, SERE_MAX_SEGMENTS, NULL },
		{ "--veins", SERE_OPTION_COUNT, &veins, 0, 64, NULL },
		{ "--vein-segments", SERE_OPTION_COUNT, &vein_segments, 1, SERE_MAX_SEGMENTS, NULL },
		{ "--vein-angle", SERE_OPTION_REAL, &vein_angle, 1.0, 179.0, NULL },
		{ "--mid-bend", SERE_OPTION_REAL, &mid_bend, 0.0, 180.0, NULL },
		{ "--vein-bend", SERE_OPTION_REAL, &vein_bend, 0.0, 180.0, NULL },
		{ "--droop", SERE_OPTION_REAL, &droop, 0.0, 1e6, NULL },
		{ "--min-angle", SERE_OPTION_REAL, &min_angle, 0.0, 180.0, NULL },
		{ "--spread", SERE_OPTION_REAL, &spread, 0.0, 0.99, NULL },
		{ "--no-pierce", SERE_OPTION_FLAG, &no_pierce, 0, 0, NULL },
		{ "--leaves", SERE_OPTION_COUNT, &o->leaves, 1, 10000, NULL },
		{ "--stagger", SERE_OPTION_REAL, &o->stagger, 0.0, 100.0, NULL },
		{ "--internode", SERE_OPTION_REAL, &o->internode, 0.0, 1e6, NULL },
		{ "--elevation", SERE_OPTION_REAL, &o->elevation, -80.0, 80.0, NULL },
		{ "--frames", SERE_OPTION_COUNT, &o->frames, 1, 1000000, NULL },
		{ "--speed", SERE_OPTION_REAL, &o->speed, 0.0, 100.0, NULL },
		sere_option_out( &o->out ),
		{ "--format", SERE_OPTION_TEXT, &format, 0, 0, NULL },
		{ "--every", SERE_OPTION_COUNT, &o->every, 1, 1000000, NULL },
		{ "--size", SERE_OPTION_TEXT, &size, 0, 0, NULL },
		{ "--view", SERE_OPTION_TEXT, &view, 0, 0, NULL },
		sere_option_threads( &o->threads ),
		sere_option_json( &o->json ),
	};
	int code = sere_options_read( "wilt", argc, argv, options, sizeof( options ) / sizeof( options[0] ), "SKELETON",
								  &o->skeleton, wilt_help );
	if ( code != SERE_OPTIONS_GO )
	{
		return code;
	}
	o->wilt.pierce = no_pierce ? 0 : o->wilt.pierce;
	o->venation.mid_segments = mid_segments > 0 ? (int32_t) mid_segments : o->venation.mid_segments;
	o->venation.secondary_count = veins >= 0 ? (int32_t) veins : o->venation.secondary_count;
	o->venation.secondary_segments = vein_segments > 0 ? (int32_t) vein_segments : o->venation.secondary_segments;
	o->venation.angle = isnan( vein_angle ) ? o->venation.angle : (float) ( vein_angle * PI / 180.0 );
	o->venation.mid_bend = isnan( mid_bend ) ? o->venation.mid_bend : (float) ( mid_bend * PI / 180.0 );
	o->venation.secondary_bend = isnan( vein_bend ) ? o->venation.secondary_bend : (float) ( vein_bend * PI / 180.0 );
	o->wilt.droop_max = isnan( droop ) ? o->wilt.droop_max : (float) droop;
	o->wilt.min_angle = isnan( min_angle ) ? o->wilt.min_angle : (float) ( min_angle * PI / 180.0 );
	o->wilt.spread = isnan( spread ) ? o->wilt.spread : (float) spread;
	if ( ( format != NULL && parse_format( format, o ) != 0 ) ||
		 ( size != NULL && parse_pair( "--size", size, 'x', 64, 8192, &o->size[0], &o->size[1] ) != 0 ) ||
		 ( view != NULL && parse_pair( "--view", view, ',', -360.0, 360.0, &o->view[0], &o->view[1] ) != 0 ) )
	{
		return 2;
	}
	if ( fabs( o->view[1] ) > 89.0 )
	{
		fprintf( stderr, "sere wilt: --view elevation must lie within +-89 degrees, not '%s'\n", view );
		return 2;
	}
	return SERE_OPTIONS_GO;
}

typedef struct wilt_run
{
	skeleton_file file;
	int have_file;
	double* parametric; /* 6 * features doubles: left, right, mid */
	sere_tri_mesh blade, mesh;
	sere_skeleton skeleton;
	sere_plant* plant;
	int threads; /* the kernels' (sere_topo_bind's count) */
	sere_bvh* check_bvh;
	wilt_picture picture;
	char** names;
	double* times;
	int32_t written;
} wilt_run;

static void wilt_run_free( wilt_run* r )
{
	if ( r->have_file )
	{
		wilt_skeleton_free( &r->file );
	}
	free( r->parametric );
	sere_tri_mesh_destroy( &r->blade );
	sere_tri_mesh_destroy( &r->mesh );
	sere_skeleton_destroy( &r->skeleton );
	sere_plant_destroy( r->plant );
	sere_bvh_destroy( r->check_bvh );
	wilt_picture_free( &r->picture );
	for ( int32_t k = 0; k < r->written; ++k )
	{
		free( r->names[k] );
	}
	free( r->names );
	free( r->times );
}

/* Writes one frame's files; 0 on success, else -1 with a message printed. */
static int write_frame( const wilt_options* o, wilt_run* r, int64_t frame, double time, const float* stem, float* droop,
						float* leaf_t )
{
	const sere_plant* p = r->plant;
	char path[4096];
	for ( int32_t k = 0; k < p->leaf_count; ++k )
	{
		for ( int32_t i = p->vertex_first[k]; i < p->vertex_first[k + 1]; ++i )
		{
			droop[i] = p->rz[i] - p->z[i];
			leaf_t[i] = p->leaf_t[k];
		}
	}
	sere_vertex_property props[4] = { { "u", p->u }, { "v", p->v }, { "droop", droop }, { "wilt_t", leaf_t } };
	if ( o->ply )
	{
		snprintf( path, sizeof( path ), "%s/frame_%04lld.ply", o->out, (long long) frame );
		if ( sere_ply_write( path, p->x, p->y, p->z, p->vertex_count, p->tri, p->triangle_count, NULL, props, 4 ) != 0 )
		{
			fprintf( stderr, "sere wilt: cannot write %s: %s\n", path, strerror( errno ) );
			return -1;
		}
	}
	if ( o->vtp )
	{
		char name[64];
		snprintf( name, sizeof( name ), "frame_%04lld.vtp", (long long) frame );
		snprintf( path, sizeof( path ), "%s/%s", o->out, name );
		if ( sere_vtp_write( path, p->x, p->y, p->z, p->vertex_count, p->tri, p->triangle_count, props, 4 ) != 0 )
		{
			fprintf( stderr, "sere wilt: cannot write %s: %s\n", path, strerror( errno ) );
			return -1;
		}
		r->names[r->written] = strdup( name );
		if ( r->names[r->written] == NULL )
		{
			fprintf( stderr, "sere wilt: out of memory\n" );
			return -1;
		}
		r->times[r->written++] = time;
		snprintf( path, sizeof( path ), "%s/wilt.pvd", o->out );
		if ( sere_pvd_write( path, (const char* const*) r->names, r->times, r->written ) != 0 )
		{
			fprintf( stderr, "sere wilt: cannot write %s: %s\n", path, strerror( errno ) );
			return -1;
		}
	}
	if ( o->png )
	{
		snprintf( path, sizeof( path ), "%s/frame_%04lld.png", o->out, (long long) frame );
		char err[4400];
		if ( wilt_picture_png( path, &r->picture, p, stem, o->frames > 1 ? (double) frame / ( o->frames - 1 ) : 1.0,
							   err, sizeof( err ) ) != 0 )
		{
			fprintf( stderr, "sere wilt: %s\n", err );
			return -1;
		}
	}
	return 0;
}

/* Builds the leaf template: leaf skeleton (file or parametric), blade mesh, subdivision and
 * venation skeleton. 0 on success, else 1 with one line printed. */
static int build_leaf( const wilt_options* o, wilt_run* r, double* leaf_length )
{
	char err[4600], where[4300];
	sere_leaf_skeleton leaf;
	if ( o->skeleton != NULL )
	{
		if ( wilt_skeleton_load( o->skeleton, &r->file, err, sizeof( err ) ) != 0 )
		{
			fprintf( stderr, "sere wilt: %s\n", err );
			return 1;
		}
		r->have_file = 1;
		leaf = ( sere_leaf_skeleton ){ r->file.curve[0].count, r->file.curve[1].count, r->file.curve[2].count,
									   r->file.curve[0].xy,	   r->file.curve[1].xy,	   r->file.curve[2].xy };
	}
	else
	{
		int32_t n = (int32_t) o->features;
		r->parametric = malloc( 6 * (size_t) n * sizeof( double ) );
		if ( r->parametric == NULL ||
			 sere_leaf_skeleton_generate( o->length, o->width, n, r->parametric, r->parametric + 2 * n,
										  r->parametric + 4 * n ) != SERE_OK )
		{
			fprintf( stderr, "sere wilt: cannot make the parametric leaf (length %g, width %g, %d feature points)\n",
					 o->length, o->width, n );
			return 1;
		}
		leaf = ( sere_leaf_skeleton ){ n, n, n, r->parametric, r->parametric + 2 * n, r->parametric + 4 * n };
	}
	const skeleton_file* file = r->have_file ? &r->file : NULL;
	const double* mid = leaf.mid_xy;
	*leaf_length = hypot( mid[2 * leaf.mid_count - 2] - mid[0], mid[2 * leaf.mid_count - 1] - mid[1] );
	double spacing = o->spacing > 0.0 ? o->spacing : *leaf_length / 25.0;
	sere_skeleton_check check = { SERE_SKELETON_OK, -1, -1 };
	sere_status status = sere_leaf_skeleton_mesh( &leaf, spacing, &r->blade, &check );
	if ( status != SERE_OK )
	{
		if ( check.problem != SERE_SKELETON_OK )
		{
			wilt_skeleton_where( file, &check, 0, where, sizeof( where ) );
			fprintf( stderr, "sere wilt: %s%s\n", where, sere_skeleton_problem_text( check.problem ) );
		}
		else
		{
			fprintf( stderr, "sere wilt: %s: cannot mesh the blade: %s\n", file ? file->path : "parametric leaf",
					 sere_status_text( status ) );
		}
		return 1;
	}
	status = sere_subdivide( &r->blade, (int32_t) o->subdivide, (float) o->min_edge, &r->mesh );
	if ( status != SERE_OK )
	{
		fprintf( stderr, "sere wilt: cannot subdivide the blade %lld times: %s\n", o->subdivide,
				 sere_status_text( status ) );
		return 1;
	}
	if ( file != NULL && file->vein_count > 0 )
	{
		sere_vein_spec veins[MAX_VEINS];
		for ( int32_t k = 0; k < file->vein_count; ++k )
		{
			const point_list* p = file->vein + k;
			/* The midvein block may leave its points to the leaf skeleton's midvein. */
			int follow = k == 0 && p->count == 0;
			veins[k] = ( sere_vein_spec ){ file->vein_parent[k], file->vein_segments[k],
										   (float) ( file->vein_bend[k] * PI / 180.0 ),
										   follow ? leaf.mid_count : p->count, follow ? leaf.mid_xy : p->xy };
		}
		status = sere_skeleton_create( veins, file->vein_count, &r->skeleton, &check );
		if ( status != SERE_OK )
		{
			wilt_skeleton_where( file, &check, 1, where, sizeof( where ) );
			fprintf( stderr, "sere wilt: %s%s\n", where, sere_skeleton_problem_text( check.problem ) );
			return 1;
		}
	}
	else
	{
		status = sere_skeleton_generate( &leaf, &o->venation, &r->skeleton, &check );
		if ( status != SERE_OK )
		{
			fprintf( stderr, "sere wilt: %s: cannot generate the venation: %s\n", file ? file->path : "parametric leaf",
					 check.problem != SERE_SKELETON_OK ? sere_skeleton_problem_text( check.problem )
													   : sere_status_text( status ) );
			return 1;
		}
	}
	return 0;
}

/* What a run measured, for the summary. */
typedef struct wilt_summary
{
	int threads;
	int32_t leaves;
	double speed;
	double setup, simulate, output; /* seconds */
	sere_wilt_stats total;
	double deepest;
	int64_t intersections;
} wilt_summary;

/* The plant (Sec. 7): leaves up the stem 137.5° apart, the upper ones a little smaller, each
 * starting to wilt `stagger` after the one below. stem gets [2] its top, [3] its bottom and [4]
 * the petiole length (for the petiole nodes). */
static int build_plant( const wilt_options* o, wilt_run* r, double leaf_length, float stem[5] )
{
	int32_t leaves = (int32_t) o->leaves;
	double internode = o->internode >= 0.0 ? o->internode : 0.3 * leaf_length;
	sere_leaf_placement* placement = calloc( (size_t) leaves, sizeof( sere_leaf_placement ) );
	if ( placement == NULL )
	{
		fprintf( stderr, "sere wilt: out of memory\n" );
		return 1;
	}
	double base_height = leaves > 1 ? 0.5 * leaf_length : 0.0;
	for ( int32_t k = 0; k < leaves; ++k )
	{
		double azimuth = k * 137.5 * PI / 180.0;
		double petiole = leaves > 1 ? 0.12 * leaf_length : 0.0;
		placement[k].template_index = 0;
		placement[k].base[0] = (float) ( petiole * cos( azimuth ) );
		placement[k].base[1] = (float) ( petiole * sin( azimuth ) );
		placement[k].base[2] = (float) ( base_height + k * internode + 0.3 * petiole );
		placement[k].azimuth = (float) azimuth;
		placement[k].elevation = (float) ( o->elevation * PI / 180.0 );
		placement[k].scale = (float) ( leaves > 1 ? 1.0 - 0.35 * k / ( leaves - 1 ) : 1.0 );
		placement[k].onset = (float) ( o->stagger * k );
	}
	sere_leaf_template template = { &r->mesh, &r->skeleton };
	sere_status status = sere_plant_create( &template, 1, placement, leaves, &r->plant );
	free( placement );
	status = status == SERE_OK ? sere_plant_set_threads( r->plant, r->threads ) : status;
	if ( status != SERE_OK )
	{
		fprintf( stderr, "sere wilt: cannot build the plant of %d leaves: %s\n", leaves, sere_status_text( status ) );
		return 1;
	}
	stem[0] = stem[1] = 0.0f;
	stem[2] = (float) ( base_height + ( leaves - 1 ) * internode + 0.05 * leaf_length );
	stem[3] = 0.0f;
	stem[4] = (float) ( leaves > 1 ? 0.12 * leaf_length : 0.0 );
	return 0;
}

/* Every frame: wilt, then write the frames asked for; sums the statistics and the times. */
static int run_frames( const wilt_options* o, wilt_run* r, const float stem[5], wilt_summary* s )
{
	sere_plant* plant = r->plant;
	int64_t pictures = ( o->frames - 1 ) / o->every + 1 + ( ( o->frames - 1 ) % o->every != 0 );
	float* droop = calloc( (size_t) plant->vertex_count, sizeof( float ) );
	float* leaf_t = calloc( (size_t) plant->vertex_count, sizeof( float ) );
	r->names = calloc( (size_t) pictures, sizeof( char* ) );
	r->times = calloc( (size_t) pictures, sizeof( double ) );
	if ( droop == NULL || leaf_t == NULL || r->names == NULL || r->times == NULL )
	{
		fprintf( stderr, "sere wilt: out of memory\n" );
		free( droop );
		free( leaf_t );
		return 1;
	}
	char err[256];
	if ( o->png && wilt_picture_fit( &r->picture, o->view[0], o->view[1], (int) o->size[0], (int) o->size[1], plant,
									 err, sizeof( err ) ) != 0 )
	{
		fprintf( stderr, "%s\n", err );
		free( droop );
		free( leaf_t );
		return 1;
	}
	sere_progress progress;
	sere_progress_begin( &progress, "wilt", o->frames );
	int failed = 0;
	for ( int64_t frame = 0; frame < o->frames && !failed; ++frame )
	{
		double time = s->speed * (double) frame;
		double t0 = sere_now();
		sere_wilt_stats stats;
		sere_status status = sere_plant_frame( plant, (float) time, &o->wilt, &stats );
		s->simulate += sere_now() - t0;
		if ( status != SERE_OK )
		{
			fprintf( stderr, "sere wilt: frame %lld failed: %s\n", (long long) frame, sere_status_text( status ) );
			failed = 1;
			break;
		}
		s->total.pose.droop_limited += stats.pose.droop_limited;
		s->total.pose.angle_limited += stats.pose.angle_limited;
		s->total.pose.down_limited += stats.pose.down_limited;
		s->total.pierce.shortened += stats.pierce.shortened;
		s->total.pierce.pulled_back += stats.pierce.pulled_back;
		s->total.pierce.reverted += stats.pierce.reverted;
		if ( o->out != NULL && ( frame % o->every == 0 || frame == o->frames - 1 ) )
		{
			double t1 = sere_now();
			failed = write_frame( o, r, frame, time, stem, droop, leaf_t ) != 0;
			s->output += sere_now() - t1;
		}
		sere_progress_update( &progress, frame + 1 );
	}
	sere_progress_end( &progress );
	free( droop );
	free( leaf_t );
	return failed;
}

/* The final mesh checked for self-intersection with a fresh BVH (Sec. 6), and the deepest
 * joint droop. */
static void final_check( wilt_run* r, wilt_summary* s )
{
	const sere_plant* plant = r->plant;
	s->intersections = -1;
	if ( sere_bvh_create( plant->tri, plant->triangle_count, plant->vertex_count, plant->x, plant->y, plant->z,
						  &r->check_bvh ) == SERE_OK )
	{
		s->intersections = sere_mesh_count_intersections( r->check_bvh, plant->tri, plant->triangle_count, plant->x,
														  plant->y, plant->z, s->threads );
	}
	s->deepest = 0.0;
	for ( int32_t j = 0; j < plant->joints.joint_count; ++j )
	{
		s->deepest = fmax( s->deepest, (double) plant->joints.z[j] - plant->frames.z[j] );
	}
}

static void print_summary( const wilt_options* o, const wilt_run* r, const wilt_summary* s )
{
	const sere_plant* plant = r->plant;
	const sere_wilt_stats* total = &s->total;
	const char* name = r->have_file ? r->file.name : "parametric";
	double per_frame = 1e3 * s->simulate / (double) o->frames;
	if ( o->json )
	{
		char name_json[6 * sizeof( r->file.name )], out_json[6 * 4096];
		sere_json_escape( name_json, sizeof( name_json ), name );
		sere_json_escape( out_json, sizeof( out_json ), o->out );
		printf(
			"{\"leaf\": \"%s\", \"leaves\": %d, \"blade_vertices\": %d, \"blade_triangles\": %d, "
			"\"leaf_vertices\": %d, \"leaf_triangles\": %d, \"joints_per_leaf\": %d, \"veins_per_leaf\": %d, "
			"\"vertices\": %d, \"triangles\": %d, \"frames\": %lld, \"speed\": %.6g, \"threads\": %d, \"setup_ms\": "
			"%.3f, \"frame_ms\": %.3f, \"output_ms\": %.3f, \"droop_limited\": %d, \"angle_limited\": %d, "
			"\"down_limited\": %d, \"pierce_shortened\": %d, \"pulled_back\": %d, \"reverted_frames\": %d, "
			"\"deepest_joint_droop\": %.6g, \"self_intersections\": %lld, \"out\": %s%s%s}\n",
			name_json, s->leaves, r->blade.vertex_count, r->blade.triangle_count, r->mesh.vertex_count,
			r->mesh.triangle_count, r->skeleton.joint_count, r->skeleton.vein_count, plant->vertex_count,
			plant->triangle_count, o->frames, s->speed, s->threads, 1e3 * s->setup, per_frame,
			1e3 * s->output / (double) o->frames, total->pose.droop_limited, total->pose.angle_limited,
			total->pose.down_limited, total->pierce.shortened, total->pierce.pulled_back, total->pierce.reverted,
			s->deepest, (long long) s->intersections, o->out ? "\"" : "", o->out ? out_json : "null",
			o->out ? "\"" : "" );
		return;
	}
	printf( "leaf            %s: blade %d vertices / %d triangles, after %lld subdivision(s) %d / %d\n", name,
			r->blade.vertex_count, r->blade.triangle_count, o->subdivide, r->mesh.vertex_count,
			r->mesh.triangle_count );
	printf( "venation        %d veins, %d joints per leaf\n", r->skeleton.vein_count, r->skeleton.joint_count );
	printf( "plant           %d leaves, %d vertices, %d triangles\n", s->leaves, plant->vertex_count,
			plant->triangle_count );
	printf( "run             %lld frames, t += %.4g per frame, %d threads\n", o->frames, s->speed, s->threads );
	printf( "time            setup %.1f ms, %.3f ms per frame (pose, skin%s)%s\n", 1e3 * s->setup, per_frame,
			o->wilt.pierce ? ", piercing check" : "", o->out ? ", output written separately" : "" );
	printf( "limits          droop %d, angle %d, straight down %d (joint-frames held back)\n",
			total->pose.droop_limited, total->pose.angle_limited, total->pose.down_limited );
	printf( "piercing        %s: %d moves shortened, %d vertices pulled back, %d frames undone\n",
			o->wilt.pierce ? "on" : "off", total->pierce.shortened, total->pierce.pulled_back, total->pierce.reverted );
	printf( "result          deepest joint droop %.4g, self-intersecting triangle pairs %lld\n", s->deepest,
			(long long) s->intersections );
	if ( o->out != NULL )
	{
		printf( "output          %s (%s%s%s)\n", o->out, o->ply ? "ply " : "", o->vtp ? "vtp+pvd " : "",
				o->png ? "png" : "" );
	}
}

int sere_cmd_wilt( int argc, char** argv )
{
	wilt_options o;
	int code = parse_options( argc, argv, &o );
	if ( code != SERE_OPTIONS_GO )
	{
		return code;
	}
	if ( o.out != NULL && sere_dir_create( o.out ) != 0 )
	{
		fprintf( stderr, "sere wilt: cannot create output directory '%s': %s\n", o.out, strerror( errno ) );
		return 1;
	}
	wilt_summary s;
	memset( &s, 0, sizeof( s ) );
	s.threads = sere_topo_bind( (int) o.threads, NULL );
	s.leaves = (int32_t) o.leaves;
	double start = sere_now();
	wilt_run r;
	memset( &r, 0, sizeof( r ) );
	r.threads = s.threads;
	double leaf_length = 0.0;
	float stem[5];
	if ( build_leaf( &o, &r, &leaf_length ) != 0 || build_plant( &o, &r, leaf_length, stem ) != 0 )
	{
		wilt_run_free( &r );
		return 1;
	}
	s.setup = sere_now() - start;
	s.speed = o.speed >= 0.0 ? o.speed : ( 1.0 + o.stagger * ( s.leaves - 1 ) ) / fmax( 1.0, (double) o.frames - 1 );
	if ( run_frames( &o, &r, stem, &s ) != 0 )
	{
		wilt_run_free( &r );
		return 1;
	}
	final_check( &r, &s );
	print_summary( &o, &r, &s );
	wilt_run_free( &r );
	return 0;
}
