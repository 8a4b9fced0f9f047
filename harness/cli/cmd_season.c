/* sere season — seasonal leaves on a tree (seed 002, Tang, Wu & Fan 2013): the leaf from key
 * points and a mask map with its mass-spring deformation levels, a tree from an L-system, and
 * the Markov chain of leaf states stepped once a day under a temperature/humidity schedule. */
#define _POSIX_C_SOURCE 200809L
#include "cli/cmd_season_shared.h"
#include "cli/commands.h"
#include "cli/options.h"
#include "common/io.h"
#include "common/params.h"
#include "common/topo.h"
#include "read/seasonleaf.h"
#include "render/render.h"
#include "season/lsystem.h"
#include "season/markov.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define PI 3.14159265358979323846
/* Leaf length in tree units (the first branch segment is 1 long). */
#define LEAF_SIZE 0.34f
/* Sides of the prism drawn for a branch segment. */
#define BRANCH_SIDES 6

/* ------------------------------------------------------------------------------------------- */
/* Options. */

typedef struct options
{
	const char* chain;
	const char* schedule;
	const char* keys;
	const char* silhouette;
	const char* mask;
	const char* out;
	long long days;
	double temperature, humidity;
	int have_weather;
	long long leaves;
	long long seed;
	long long threads;
	long long iterations;
	long long optimize;
	long long samples;
	long long steps;
	long long size;
	int pictures;
} options;

static void season_help( void )
{
	printf(
		"usage: sere season [options]\n\n"
		"Seasonal changes of a tree's leaves (Tang, Wu & Fan 2013). The leaf: key points on its edge, a closed\n"
		"B-spline through them, Delaunay triangulation and mesh optimization, masses from a grayscale mask map\n"
		"(Tang Eq. 3) and deformation levels by the mass-spring model. The tree: an L-system. The leaves: a Markov\n"
		"chain of (texture, deformation) states stepped once a day, with probabilities from the day's\n"
		"temperature and humidity (Tang Eq. 5-6), for a population of leaves of which the tree shows the first.\n\n"
		"chain and weather:\n"
		"  --chain FILE        states and transitions (default data/seasons/maple.chain; the format is in it)\n"
		"  --schedule FILE     DAY TEMPERATURE HUMIDITY [LABEL] lines (default data/seasons/temperate.schedule)\n"
		"  --days N --temperature T --humidity H\n"
		"                      constant weather for N days instead of a schedule (pictures on day 0 and N)\n"
		"  --leaves N          leaves stepped per day (default 1000000; the tree shows the first of them)\n"
		"  --seed S            random seed (default 1); results depend on it, never on --threads\n"
		"leaf:\n"
		"  --keys FILE         key points (default data/seasons/maple.keys) or\n"
		"  --silhouette PNG    a leaf silhouette on white to take them from\n"
		"  --mask FILE         grayscale mask map, PGM or PNG, in the key points' pixel frame\n"
		"                      (default data/masks/maple.pgm)\n"
		"  --samples N         outline samples of the tree's leaf mesh (default 48)\n"
		"  --optimize N        mesh optimization iterations (default 160, the seed's)\n"
		"  --steps N           mass-spring steps per deformation level (default 400)\n"
		"tree and output:\n"
		"  --iterations N      L-system rewriting steps (default 6: about 1100 leaves)\n"
		"  --out DIR           output directory (default out/season)\n"
		"  --size PX           picture size (default 900)\n"
		"  --no-pictures       CSV, PLY and summary only\n"
		"  --threads T         OpenMP threads, 0 = one per core (default 0)\n\n"
		"writes distribution.csv (exact and sampled share of every state per day), distribution.png,\n"
		"tree_LABEL.ply and season_LABEL.png per labeled day, seasons.png (all of them), leaf_levels.png and\n"
		"summary.json.\n" );
}

/* SERE_OPTIONS_GO to run, else the exit code: 0 after --help, 2 for bad input. */
static int parse_options( int argc, char** argv, options* o )
{
	*o = ( options ){ .chain = "seasons/maple.chain",
					  .schedule = NULL,
					  .keys = NULL,
					  .mask = "masks/maple.pgm",
					  .out = "out/season",
					  .days = -1,
					  .temperature = NAN,
					  .humidity = NAN,
					  .leaves = 1000000,
					  .seed = 1,
					  .iterations = 6,
					  .optimize = 160,
					  .samples = 48,
					  .steps = 400,
					  .size = 900,
					  .pictures = 1 };
	int no_pictures = 0;
	const sere_option table[] = {
		{ "--chain", SERE_OPTION_TEXT, &o->chain, 0, 0, NULL },
		{ "--schedule", SERE_OPTION_TEXT, &o->schedule, 0, 0, NULL },
		{ "--keys", SERE_OPTION_TEXT, &o->keys, 0, 0, NULL },
		{ "--silhouette", SERE_OPTION_TEXT, &o->silhouette, 0, 0, NULL },
		{ "--mask", SERE_OPTION_TEXT, &o->mask, 0, 0, NULL },
		sere_option_out( &o->out ),
		{ "--days", SERE_OPTION_COUNT, &o->days, 1, MAX_DAYS, NULL },
		{ "--temperature", SERE_OPTION_REAL, &o->temperature, -90.0, 70.0, NULL },
		{ "--humidity", SERE_OPTION_REAL, &o->humidity, 0.0, 1.0, NULL },
		{ "--leaves", SERE_OPTION_COUNT, &o->leaves, 1, 1000000000, NULL },
		{ "--seed", SERE_OPTION_COUNT, &o->seed, 0, 2147483647, NULL },
		sere_option_threads( &o->threads ),
		{ "--iterations", SERE_OPTION_COUNT, &o->iterations, 0, 9, NULL },
		{ "--samples", SERE_OPTION_COUNT, &o->samples, 8, 2000, NULL },
		{ "--optimize", SERE_OPTION_COUNT, &o->optimize, 0, 10000, NULL },
		{ "--steps", SERE_OPTION_COUNT, &o->steps, 0, 100000, NULL },
		{ "--size", SERE_OPTION_COUNT, &o->size, 200, 4000, NULL },
		{ "--no-pictures", SERE_OPTION_FLAG, &no_pictures, 0, 0, NULL },
	};
	int code =
		sere_options_read( "season", argc, argv, table, sizeof( table ) / sizeof( table[0] ), NULL, NULL, season_help );
	if ( code != SERE_OPTIONS_GO )
	{
		return code;
	}
	o->pictures = !no_pictures;
	int constant = o->days > 0 || isfinite( o->temperature ) || isfinite( o->humidity );
	if ( constant && ( o->days < 0 || !isfinite( o->temperature ) || !isfinite( o->humidity ) ) )
	{
		fprintf( stderr, "sere season: constant weather needs all of --days, --temperature and --humidity\n" );
		return 2;
	}
	if ( constant && o->schedule != NULL )
	{
		fprintf( stderr, "sere season: give --schedule or constant weather (--days ...), not both\n" );
		return 2;
	}
	if ( o->keys != NULL && o->silhouette != NULL )
	{
		fprintf( stderr, "sere season: give --keys or --silhouette, not both\n" );
		return 2;
	}
	o->have_weather = constant;
	if ( !constant && o->schedule == NULL )
	{
		o->schedule = "seasons/temperate.schedule";
	}
	if ( o->keys == NULL && o->silhouette == NULL )
	{
		o->keys = "seasons/maple.keys";
	}
	return SERE_OPTIONS_GO;
}

/* ------------------------------------------------------------------------------------------- */
/* The tree as one colored triangle mesh: prisms for the branches, the leaves' level meshes
 * placed in their frames, fallen leaves scattered under the crown. */

typedef struct scene
{
	int32_t vertex_count, triangle_count;
	float *x, *y, *z;
	uint8_t* rgb;
	float* state; /* per vertex: the leaf's state, −1 on branches */
	int32_t* tri;
} scene;

static void scene_free( scene* s )
{
	free( s->x ), free( s->y ), free( s->z ), free( s->rgb ), free( s->state ), free( s->tri );
	memset( s, 0, sizeof( *s ) );
}

static uint64_t hash64( uint64_t z )
{
	z = ( z ^ ( z >> 30 ) ) * 0xBF58476D1CE4E5B9ull;
	z = ( z ^ ( z >> 27 ) ) * 0x94D049BB133111EBull;
	return z ^ ( z >> 31 );
}

static double unit_random( uint64_t seed, uint64_t i )
{
	return (double) ( hash64( seed ^ hash64( i ) ) >> 11 ) / 9007199254740992.0;
}

static sere_status build_scene( const sere_tree* tree, const sere_season_leaf* leaf, const chain_file* c,
								const uint8_t* states, double crown, uint64_t seed, scene* s )
{
	const int32_t nv = leaf->vertex_count, nt = leaf->triangle_count;
	const int64_t vertices = (int64_t) tree->segment_count * 2 * BRANCH_SIDES + (int64_t) tree->leaf_count * nv;
	const int64_t triangles = (int64_t) tree->segment_count * 2 * BRANCH_SIDES + (int64_t) tree->leaf_count * nt;
	if ( vertices > INT32_MAX / 4 || triangles > INT32_MAX / 4 )
	{
		fprintf( stderr, "sere season: the tree is too large to draw (%lld vertices)\n", (long long) vertices );
		return SERE_ERR_CAPACITY;
	}
	s->x = malloc( sizeof( float ) * (size_t) vertices );
	s->y = malloc( sizeof( float ) * (size_t) vertices );
	s->z = malloc( sizeof( float ) * (size_t) vertices );
	s->rgb = malloc( 3 * (size_t) vertices );
	s->state = malloc( sizeof( float ) * (size_t) vertices );
	s->tri = malloc( sizeof( int32_t ) * 3 * (size_t) triangles );
	if ( s->x == NULL || s->y == NULL || s->z == NULL || s->rgb == NULL || s->state == NULL || s->tri == NULL )
	{
		scene_free( s );
		fprintf( stderr, "sere season: out of memory for the tree's mesh\n" );
		return SERE_ERR_MEMORY;
	}
	int32_t v = 0, t = 0;
	for ( int32_t k = 0; k < tree->segment_count; ++k )
	{
		double a[3] = { tree->x0[k], tree->y0[k], tree->z0[k] }, b[3] = { tree->x1[k], tree->y1[k], tree->z1[k] };
		double d[3] = { b[0] - a[0], b[1] - a[1], b[2] - a[2] };
		double len = sqrt( d[0] * d[0] + d[1] * d[1] + d[2] * d[2] );
		d[0] /= len, d[1] /= len, d[2] /= len;
		double e[3] = { fabs( d[2] ) < 0.9 ? 0.0 : 1.0, 0.0, fabs( d[2] ) < 0.9 ? 1.0 : 0.0 };
		double p[3] = { d[1] * e[2] - d[2] * e[1], d[2] * e[0] - d[0] * e[2], d[0] * e[1] - d[1] * e[0] };
		double pn = sqrt( p[0] * p[0] + p[1] * p[1] + p[2] * p[2] );
		p[0] /= pn, p[1] /= pn, p[2] /= pn;
		double q[3] = { d[1] * p[2] - d[2] * p[1], d[2] * p[0] - d[0] * p[2], d[0] * p[1] - d[1] * p[0] };
		for ( int side = 0; side < BRANCH_SIDES; ++side )
		{
			double angle = 2.0 * PI * side / BRANCH_SIDES, cs = cos( angle ), sn = sin( angle );
			for ( int end = 0; end < 2; ++end )
			{
				double r = end == 0 ? tree->r0[k] : tree->r1[k];
				const double* o = end == 0 ? a : b;
				int32_t i = v + 2 * side + end;
				s->x[i] = (float) ( o[0] + r * ( cs * p[0] + sn * q[0] ) );
				s->y[i] = (float) ( o[1] + r * ( cs * p[1] + sn * q[1] ) );
				s->z[i] = (float) ( o[2] + r * ( cs * p[2] + sn * q[2] ) );
				s->rgb[3 * i] = 92, s->rgb[3 * i + 1] = 70, s->rgb[3 * i + 2] = 52;
				s->state[i] = -1.0f;
			}
			int32_t a0 = v + 2 * side, a1 = a0 + 1, b0 = v + 2 * ( ( side + 1 ) % BRANCH_SIDES ), b1 = b0 + 1;
			int32_t* tr = s->tri + 3 * t;
			tr[0] = a0, tr[1] = b0, tr[2] = b1, tr[3] = a0, tr[4] = b1, tr[5] = a1;
			t += 2;
		}
		v += 2 * BRANCH_SIDES;
	}
	for ( int32_t k = 0; k < tree->leaf_count; ++k )
	{
		const int32_t st = states[k];
		const float* shape = leaf->xyz + 3 * (size_t) nv * (size_t) c->level[st];
		double origin[3], dir[3], nrm[3];
		if ( c->fallen[st] )
		{
			/* on the ground under the crown, blade up, at a place and turn of its own */
			double r = crown * sqrt( unit_random( seed, 2 * (uint64_t) k ) ),
				   phi = 2.0 * PI * unit_random( seed, 2 * (uint64_t) k + 1 );
			double yaw = 2.0 * PI * unit_random( seed ^ 0x5eedu, (uint64_t) k );
			origin[0] = r * cos( phi ), origin[1] = r * sin( phi ), origin[2] = 0.02;
			dir[0] = cos( yaw ), dir[1] = sin( yaw ), dir[2] = 0.0;
			nrm[0] = 0.0, nrm[1] = 0.0, nrm[2] = 1.0;
		}
		else
		{
			origin[0] = tree->leaf_x[k], origin[1] = tree->leaf_y[k], origin[2] = tree->leaf_z[k];
			dir[0] = tree->leaf_dirx[k], dir[1] = tree->leaf_diry[k], dir[2] = tree->leaf_dirz[k];
			nrm[0] = tree->leaf_nx[k], nrm[1] = tree->leaf_ny[k], nrm[2] = tree->leaf_nz[k];
		}
		/* leaf frame: x across the blade = dir × nrm, y along it = dir, z its face normal */
		double side[3] = { dir[1] * nrm[2] - dir[2] * nrm[1], dir[2] * nrm[0] - dir[0] * nrm[2],
						   dir[0] * nrm[1] - dir[1] * nrm[0] };
		for ( int32_t i = 0; i < nv; ++i )
		{
			double lx = LEAF_SIZE * shape[3 * i], ly = LEAF_SIZE * shape[3 * i + 1], lz = LEAF_SIZE * shape[3 * i + 2];
			int32_t w = v + i;
			s->x[w] = (float) ( origin[0] + lx * side[0] + ly * dir[0] + lz * nrm[0] );
			s->y[w] = (float) ( origin[1] + lx * side[1] + ly * dir[1] + lz * nrm[1] );
			s->z[w] = (float) ( origin[2] + lx * side[2] + ly * dir[2] + lz * nrm[2] );
			memcpy( s->rgb + 3 * (size_t) w, c->rgb[st], 3 );
			s->state[w] = (float) st;
		}
		for ( int32_t j = 0; j < 3 * nt; ++j )
		{
			s->tri[3 * (size_t) t + j] = v + leaf->tri[j];
		}
		v += nv;
		t += nt;
	}
	s->vertex_count = v;
	s->triangle_count = t;
	return 0;
}

/* ------------------------------------------------------------------------------------------- */
/* Pictures. */

typedef struct season_pictures
{
	const sere_tree* tree;
	const sere_season_leaf* leaf;
	const chain_file* chain;
	const uint8_t* snapshots; /* label_count × tree leaves */
	const int32_t* label_day;
	char ( *label )[NAME_SIZE];
	int32_t label_count;
	double crown;
	uint64_t seed;
	sere_render_view view; /* fitted once on the first season, shared by all */
} season_pictures;

static sere_status draw_season( void* user, int index, cairo_t* cr, double x, double y, double w, double h,
								char* caption, size_t caption_size, char* err, size_t err_size )
{
	season_pictures* p = user;
	scene s = { 0 };
	sere_status status =
		build_scene( p->tree, p->leaf, p->chain, p->snapshots + (size_t) index * (size_t) p->tree->leaf_count, p->crown,
					 p->seed, &s );
	if ( status != SERE_OK )
	{
		return sere_fail( status, err, err_size, "cannot build the tree's mesh" );
	}
	cairo_save( cr );
	cairo_rectangle( cr, x, y, w, h );
	cairo_set_source_rgb( cr, 0.93, 0.95, 0.97 );
	cairo_fill( cr );
	cairo_restore( cr );
	sere_render_mesh mesh = {
		s.x, s.y, s.z, s.vertex_count, s.tri, s.triangle_count, NULL, s.rgb, { 0.5f, 0.5f, 0.5f }
	};
	status = sere_render_mesh_draw( cr, x, y, w, h, &mesh, &p->view, NULL, err, err_size );
	scene_free( &s );
	snprintf( caption, caption_size, "day %d: %s", p->label_day[index], p->label[index] );
	return status;
}

static sere_status write_season_png( season_pictures* p, int index, const char* path, int size, char* err,
									 size_t err_size )
{
	sere_render_canvas canvas;
	sere_status rc = sere_render_canvas_create( &canvas, size, size, err, err_size );
	if ( rc != SERE_OK )
	{
		return rc;
	}
	char caption[128];
	rc = draw_season( p, index, canvas.cr, 0, 0, size, size, caption, sizeof( caption ), err, err_size );
	if ( rc == SERE_OK )
	{
		sere_render_text( canvas.cr, 16, 32, 20, 1, 0, caption );
		rc = sere_render_canvas_write_png( &canvas, path, err, err_size );
	}
	sere_render_canvas_destroy( &canvas );
	return rc;
}

typedef struct level_pictures
{
	const sere_season_leaf* leaf;
	sere_render_view view;
} level_pictures;

static sere_status draw_level( void* user, int index, cairo_t* cr, double x, double y, double w, double h,
							   char* caption, size_t caption_size, char* err, size_t err_size )
{
	level_pictures* p = user;
	const int32_t n = p->leaf->vertex_count;
	float* xyz = malloc( sizeof( float ) * 3 * (size_t) n );
	if ( xyz == NULL )
	{
		return sere_fail( SERE_ERR_MEMORY, err, err_size, "out of memory" );
	}
	const float* src = p->leaf->xyz + 3 * (size_t) n * (size_t) index;
	for ( int32_t i = 0; i < n; ++i )
	{
		xyz[i] = src[3 * i], xyz[n + i] = src[3 * i + 1];
		xyz[2 * (size_t) n + i] = src[3 * i + 2];
	}
	float* mass_rgb = malloc( sizeof( float ) * 3 * (size_t) n );
	if ( mass_rgb == NULL )
	{
		free( xyz );
		return sere_fail( SERE_ERR_MEMORY, err, err_size, "out of memory" );
	}
	float lo = p->leaf->mass[0], hi = p->leaf->mass[0];
	for ( int32_t i = 1; i < n; ++i )
	{
		lo = fminf( lo, p->leaf->mass[i] ), hi = fmaxf( hi, p->leaf->mass[i] );
	}
	sere_render_colormap_values( p->leaf->mass, n, lo, hi > lo ? hi : lo + 1.0f, mass_rgb );
	sere_render_mesh mesh = { xyz,	xyz + n, xyz + 2 * (size_t) n, n, p->leaf->tri, p->leaf->triangle_count, mass_rgb,
							  NULL, { 0 } };
	sere_render_style style = { 1, 0, 0.0, NULL, 0 };
	sere_status rc = sere_render_mesh_draw( cr, x, y, w, h, &mesh, &p->view, &style, err, err_size );
	snprintf( caption, caption_size, "deformation level %d", index );
	free( xyz );
	free( mass_rgb );
	return rc;
}

static sere_status write_distribution_png( const char* path, const chain_file* c, const double* exact,
										   const double* sampled, int32_t days, char* err, size_t err_size )
{
	const int32_t S = c->state_count, n = days + 1;
	double* x = malloc( sizeof( double ) * (size_t) n );
	sere_render_series* series = malloc( sizeof( sere_render_series ) * 2 * (size_t) S );
	char( *names )[NAME_SIZE + 16] = malloc( sizeof( *names ) * 2 * (size_t) S );
	double* columns = malloc( sizeof( double ) * 2 * (size_t) S * (size_t) n );
	if ( x == NULL || series == NULL || names == NULL || columns == NULL )
	{
		free( x ), free( series ), free( names ), free( columns );
		return sere_fail( SERE_ERR_MEMORY, err, err_size, "out of memory" );
	}
	for ( int32_t d = 0; d < n; ++d )
	{
		x[d] = d;
	}
	for ( int32_t st = 0; st < S; ++st )
	{
		for ( int k = 0; k < 2; ++k )
		{
			double* col = columns + ( 2 * (size_t) st + k ) * (size_t) n;
			for ( int32_t d = 0; d < n; ++d )
			{
				col[d] = ( k == 0 ? exact : sampled )[(size_t) d * S + st];
			}
			sere_render_series* e = &series[2 * st + k];
			snprintf( names[2 * st + k], sizeof( names[0] ), "%s%s", c->name[st], k == 0 ? " (exact)" : "" );
			e->name = names[2 * st + k];
			e->x = x;
			e->y = col;
			e->count = n;
			for ( int j = 0; j < 3; ++j )
			{
				e->rgb[j] = c->rgb[st][j] / 255.0f * 0.85f;
			}
			e->dashed = k == 0;
		}
	}
	sere_render_axes axes = {
		"Leaf states: exact distribution (dashed) and the sampled population", "day", "share of leaves", 1, 0.0, 1.0
	};
	sere_status rc = sere_render_plot( path, 1100, 620, &axes, series, 2 * S, err, err_size );
	free( x ), free( series ), free( names ), free( columns );
	return rc;
}

/* ------------------------------------------------------------------------------------------- */

/* One run: the inputs, the leaf and the tree, and the daily shares of every state, exact
 * (propagated) and sampled (the leaves stepped). */
typedef struct season_run
{
	chain_file chain;
	schedule plan;
	int32_t days;
	int threads;
	sere_season_leaf leaf;
	double leaf_seconds;
	sere_tree tree;
	int32_t label_count;
	int32_t label_day[MAX_SCHEDULE];
	char label[MAX_SCHEDULE][NAME_SIZE];
	uint8_t* states;
	double* exact;	 /* (days + 1) x states */
	double* sampled; /* (days + 1) x states */
	double* P;
	int64_t* counts;
	uint8_t* snapshots; /* the leaves' states on each labeled day */
	sere_markov_day* day_table;
	double step_seconds, worst, crown;
	int64_t tree_vertices, tree_triangles;
} season_run;

/* The chain and the schedule (or the constant weather); 0, or 2 after printing why. */
static int read_inputs( const options* o, season_run* r )
{
	char path_buffer[4096];
	if ( season_read_chain( sere_data_resolve( o->chain, path_buffer, sizeof( path_buffer ) ), &r->chain ) != 0 )
	{
		return 2;
	}
	if ( o->have_weather )
	{
		memset( &r->plan, 0, sizeof( r->plan ) );
		r->plan.count = 2;
		r->plan.day[1] = (int32_t) o->days;
		r->plan.temperature[0] = r->plan.temperature[1] = o->temperature;
		r->plan.humidity[0] = r->plan.humidity[1] = o->humidity;
		snprintf( r->plan.label[0], NAME_SIZE, "start" );
		snprintf( r->plan.label[1], NAME_SIZE, "end" );
	}
	else if ( season_read_schedule( sere_data_resolve( o->schedule, path_buffer, sizeof( path_buffer ) ), &r->plan ) !=
			  0 )
	{
		return 2;
	}
	r->days = r->plan.day[r->plan.count - 1];
	return 0;
}

/* The leaf with as many deformation levels as the chain's states use (Tang Sec. 4), and the
 * L-system tree; 0, or 2 after printing why (nothing then to free). */
static int grow_leaf_and_tree( const options* o, season_run* r )
{
	int32_t levels = 1;
	for ( int32_t s = 0; s < r->chain.state_count; ++s )
	{
		levels = r->chain.level[s] + 1 > levels ? r->chain.level[s] + 1 : levels;
	}
	sere_season_leaf_options lo = sere_season_leaf_options_default();
	lo.keys_path = o->silhouette != NULL ? NULL : o->keys;
	lo.silhouette_path = o->silhouette;
	lo.mask_path = o->mask;
	lo.outline_samples = (int32_t) o->samples;
	lo.levels = levels;
	lo.steps_per_level = (int32_t) o->steps;
	lo.meshopt_iterations = (int32_t) o->optimize;
	lo.threads = r->threads;
	char err[1024];
	double t0 = sere_now();
	if ( sere_season_leaf_build( &lo, &r->leaf, err, sizeof( err ) ) != SERE_OK )
	{
		fprintf( stderr, "sere season: %s\n", err );
		return 2;
	}
	r->leaf_seconds = sere_now() - t0;

	sere_lsystem_params lp = sere_lsystem_params_default();
	lp.iterations = (int32_t) o->iterations;
	lp.seed = (uint64_t) o->seed;
	sere_status status = sere_tree_grow( &lp, &r->tree );
	if ( status != SERE_OK )
	{
		fprintf( stderr, "sere season: the L-system tree cannot grow (%s)\n", sere_status_text( status ) );
		sere_season_leaf_destroy( &r->leaf );
		return 2;
	}
	if ( r->tree.leaf_count > o->leaves )
	{
		fprintf( stderr, "sere season: --leaves %lld is fewer than the tree's %d leaves\n", o->leaves,
				 r->tree.leaf_count );
	}
	else if ( sere_dir_create( o->out ) != 0 )
	{
		fprintf( stderr, "sere season: cannot create %s: %s\n", o->out, strerror( errno ) );
	}
	else
	{
		return 0;
	}
	sere_tree_destroy( &r->tree );
	sere_season_leaf_destroy( &r->leaf );
	return 2;
}

/* The labeled days of the schedule and the arrays of the run; 0, or 1 after printing why. */
static int prepare_days( const options* o, season_run* r )
{
	const int32_t S = r->chain.state_count;
	for ( int32_t k = 0; k < r->plan.count; ++k )
	{
		if ( r->plan.label[k][0] != '\0' )
		{
			r->label_day[r->label_count] = r->plan.day[k];
			/* both are NAME_SIZE buffers holding a terminated string: copied whole (gcc -O1 takes
			 * snprintf between two members of one struct for an overlap) */
			memcpy( r->label[r->label_count], r->plan.label[k], NAME_SIZE );
			r->label_count += 1;
		}
	}
	r->states = malloc( (size_t) o->leaves );
	r->exact = malloc( sizeof( double ) * (size_t) S * ( (size_t) r->days + 1 ) );
	r->sampled = malloc( sizeof( double ) * (size_t) S * ( (size_t) r->days + 1 ) );
	r->P = malloc( sizeof( double ) * (size_t) S * (size_t) S );
	r->counts = malloc( sizeof( int64_t ) * (size_t) S );
	r->snapshots = malloc( (size_t) ( r->label_count > 0 ? r->label_count : 1 ) * (size_t) r->tree.leaf_count + 1 );
	r->day_table = malloc( sizeof( sere_markov_day ) );
	if ( r->states == NULL || r->exact == NULL || r->sampled == NULL || r->P == NULL || r->counts == NULL ||
		 r->snapshots == NULL || r->day_table == NULL )
	{
		fprintf( stderr, "sere season: out of memory for %lld leaves\n", o->leaves );
		return 1;
	}
	memset( r->states, r->chain.initial, (size_t) o->leaves );
	for ( int32_t s = 0; s < S; ++s )
	{
		r->exact[s] = r->sampled[s] = s == r->chain.initial;
	}
	return 0;
}

/* Day by day: the exact shares propagated by the day's matrix (Tang Eq. 5–6 under the day's
 * weather) and every leaf stepped by the same chain; the states kept on labeled days. 0, or 1
 * after printing why. */
static int step_days( const options* o, season_run* r )
{
	const int32_t S = r->chain.state_count;
	const int64_t N = o->leaves;
	sere_progress progress;
	sere_progress_begin( &progress, "days", r->days );
	int32_t next_label = 0;
	for ( int32_t d = 0; d <= r->days; ++d )
	{
		while ( next_label < r->label_count && r->label_day[next_label] == d )
		{
			memcpy( r->snapshots + (size_t) next_label * (size_t) r->tree.leaf_count, r->states,
					(size_t) r->tree.leaf_count );
			next_label += 1;
		}
		if ( d == r->days )
		{
			break;
		}
		double temperature, humidity;
		season_weather( &r->plan, d, &temperature, &humidity );
		if ( sere_markov_matrix( &r->chain.chain, temperature, humidity, r->P ) != SERE_OK ||
			 sere_markov_day_prepare( &r->chain.chain, temperature, humidity, r->day_table ) != SERE_OK )
		{
			fprintf( stderr, "sere season: day %d: no transition matrix for %g deg C, humidity %g\n", d, temperature,
					 humidity );
			return 1;
		}
		sere_markov_propagate( r->P, S, r->exact + (size_t) d * S, r->exact + (size_t) ( d + 1 ) * S );
		double t1 = sere_now();
		sere_status status =
			sere_markov_advance( r->day_table, r->states, N, 0, (uint64_t) o->seed, d, r->counts, r->threads );
		r->step_seconds += sere_now() - t1;
		if ( status != SERE_OK )
		{
			fprintf( stderr, "sere season: day %d: stepping the leaves failed (%s)\n", d, sere_status_text( status ) );
			return 1;
		}
		for ( int32_t s = 0; s < S; ++s )
		{
			r->sampled[(size_t) ( d + 1 ) * S + s] = (double) r->counts[s] / (double) N;
		}
		sere_progress_update( &progress, d + 1 );
	}
	sere_progress_end( &progress );
	return 0;
}

/* Opens o->out/name to be written atomically; NULL after printing why. */
static FILE* open_output( const options* o, const char* name, sere_atomic_file* file )
{
	char path[4096];
	snprintf( path, sizeof( path ), "%s/%s", o->out, name );
	FILE* f = sere_atomic_open( file, path );
	if ( f == NULL )
	{
		fprintf( stderr, "sere season: cannot write %s: %s\n", path, strerror( errno ) );
	}
	return f;
}

/* Renames a file of open_output into place; 0, or 1 after printing why. */
static int commit_output( sere_atomic_file* file )
{
	if ( sere_atomic_commit( file ) != SERE_OK )
	{
		fprintf( stderr, "sere season: cannot write %s\n", file->path );
		return 1;
	}
	return 0;
}

/* distribution.csv: the weather and both shares of every state, day by day; also the largest
 * gap between them. 0, or 1 after printing why. */
static int write_distribution_csv( const options* o, season_run* r )
{
	const int32_t S = r->chain.state_count;
	sere_atomic_file csv;
	FILE* f = open_output( o, "distribution.csv", &csv );
	if ( f == NULL )
	{
		return 1;
	}
	fprintf( f, "day,temperature,humidity" );
	for ( int32_t s = 0; s < S; ++s )
	{
		fprintf( f, ",exact_%s", r->chain.name[s] );
	}
	for ( int32_t s = 0; s < S; ++s )
	{
		fprintf( f, ",sampled_%s", r->chain.name[s] );
	}
	fprintf( f, "\n" );
	for ( int32_t d = 0; d <= r->days; ++d )
	{
		double temperature, humidity;
		season_weather( &r->plan, d, &temperature, &humidity );
		fprintf( f, "%d,%.4g,%.4g", d, temperature, humidity );
		for ( int k = 0; k < 2; ++k )
		{
			for ( int32_t s = 0; s < S; ++s )
			{
				fprintf( f, ",%.8f", ( k == 0 ? r->exact : r->sampled )[(size_t) d * S + s] );
			}
		}
		fprintf( f, "\n" );
		for ( int32_t s = 0; s < S; ++s )
		{
			r->worst = fmax( r->worst, fabs( r->exact[(size_t) d * S + s] - r->sampled[(size_t) d * S + s] ) );
		}
	}
	return commit_output( &csv );
}

/* The tree on every labeled day as PLY; 0, or 1 after printing why. */
static int write_trees( const options* o, season_run* r )
{
	for ( int32_t k = 0; k < r->tree.leaf_count; ++k )
	{
		r->crown = fmax( r->crown, hypot( r->tree.leaf_x[k], r->tree.leaf_y[k] ) );
	}
	for ( int32_t k = 0; k < r->label_count; ++k )
	{
		scene s = { 0 };
		if ( build_scene( &r->tree, &r->leaf, &r->chain, r->snapshots + (size_t) k * (size_t) r->tree.leaf_count,
						  r->crown, (uint64_t) o->seed, &s ) != 0 )
		{
			return 1;
		}
		char path[4096];
		sere_vertex_property property = { "state", s.state };
		snprintf( path, sizeof( path ), "%s/tree_%.31s.ply", o->out, r->label[k] );
		sere_status written =
			sere_ply_write( path, s.x, s.y, s.z, s.vertex_count, s.tri, s.triangle_count, s.rgb, &property, 1 );
		r->tree_vertices = s.vertex_count, r->tree_triangles = s.triangle_count;
		scene_free( &s );
		if ( written != SERE_OK )
		{
			fprintf( stderr, "sere season: cannot write %s\n", path );
			return 1;
		}
	}
	return 0;
}

/* season_*.png, the seasons contact sheet, the leaf's levels and the distribution plot; 0, or
 * 1 after printing why. */
static int write_pictures( const options* o, season_run* r )
{
	char path[4096], err[1024];
	season_pictures pictures = {
		&r->tree, &r->leaf,		  &r->chain, r->snapshots,		 r->label_day,
		r->label, r->label_count, r->crown,	 (uint64_t) o->seed, { -35.0, 12.0, { 0, 0, 0 }, 0.0, 24.0 }
	};
	/* fit the view on the summer tree, with the ground under the crown in the picture */
	scene s = { 0 };
	if ( r->label_count > 0 &&
		 build_scene( &r->tree, &r->leaf, &r->chain, r->snapshots, r->crown, (uint64_t) o->seed, &s ) == 0 )
	{
		sere_render_mesh mesh = { s.x, s.y, s.z, s.vertex_count, s.tri, s.triangle_count, NULL, s.rgb, { 0 } };
		sere_render_fit_view( &mesh, (double) o->size, (double) o->size, &pictures.view, err, sizeof( err ) );
		scene_free( &s );
	}
	for ( int32_t k = 0; k < r->label_count; ++k )
	{
		snprintf( path, sizeof( path ), "%s/season_%.31s.png", o->out, r->label[k] );
		if ( write_season_png( &pictures, k, path, (int) o->size, err, sizeof( err ) ) != 0 )
		{
			fprintf( stderr, "sere season: %s\n", err );
			return 1;
		}
	}
	pictures.view.scale *= 400.0 / (double) o->size;
	sere_render_sheet sheet = { "Seasons of a maple (seed 002): Markov chain of leaf states over an L-system tree",
								r->label_count < 4 ? r->label_count : 3,
								r->label_count,
								400,
								400,
								draw_season,
								&pictures };
	snprintf( path, sizeof( path ), "%s/seasons.png", o->out );
	int failed = r->label_count > 0 && sere_render_contact_sheet( path, &sheet, err, sizeof( err ) ) != 0;
	level_pictures lv = { &r->leaf, { -30.0, 35.0, { 0, 0, 0 }, 0.0, 12.0 } };
	sere_render_sheet levels_sheet = { "The leaf's deformation levels (mass-spring model; color: mass by Tang Eq. 3, "
									   "dark blue lightest, yellow heaviest)",
									   r->leaf.level_count,
									   r->leaf.level_count,
									   320,
									   320,
									   draw_level,
									   &lv };
	snprintf( path, sizeof( path ), "%s/leaf_levels.png", o->out );
	failed = failed || sere_render_contact_sheet( path, &levels_sheet, err, sizeof( err ) ) != 0;
	snprintf( path, sizeof( path ), "%s/distribution.png", o->out );
	failed =
		failed || write_distribution_png( path, &r->chain, r->exact, r->sampled, r->days, err, sizeof( err ) ) != 0;
	if ( failed )
	{
		fprintf( stderr, "sere season: %s\n", err );
		return 1;
	}
	return 0;
}

/* summary.json: the sizes, the speed and the final shares; 0, or 1 after printing why. */
static int write_summary( const options* o, const season_run* r )
{
	const int32_t S = r->chain.state_count;
	sere_atomic_file json;
	FILE* f = open_output( o, "summary.json", &json );
	if ( f == NULL )
	{
		return 1;
	}
	fprintf( f, "{\n  \"leaves\": %lld,\n  \"days\": %d,\n  \"threads\": %d,\n  \"seed\": %lld,\n", o->leaves, r->days,
			 r->threads, o->seed );
	fprintf( f,
			 "  \"leaf\": { \"vertices\": %d, \"triangles\": %d, \"levels\": %d, \"build_s\": %.4f },\n"
			 "  \"tree\": { \"segments\": %d, \"leaves\": %d, \"vertices\": %lld, \"triangles\": %lld },\n",
			 r->leaf.vertex_count, r->leaf.triangle_count, r->leaf.level_count, r->leaf_seconds, r->tree.segment_count,
			 r->tree.leaf_count, (long long) r->tree_vertices, (long long) r->tree_triangles );
	fprintf( f, "  \"markov_ms_per_day\": %.5f,\n  \"leaves_per_second\": %.6g,\n", 1e3 * r->step_seconds / r->days,
			 (double) o->leaves * r->days / r->step_seconds );
	fprintf( f, "  \"max_abs_sampled_minus_exact\": %.3g,\n  \"final\": {", r->worst );
	for ( int32_t s = 0; s < S; ++s )
	{
		char name_json[6 * NAME_SIZE];
		fprintf( f, "%s\n    \"%s\": { \"exact\": %.6f, \"sampled\": %.6f }", s > 0 ? "," : "",
				 sere_json_escape( name_json, sizeof( name_json ), r->chain.name[s] ),
				 r->exact[(size_t) r->days * S + s], r->sampled[(size_t) r->days * S + s] );
	}
	fprintf( f, "\n  }\n}\n" );
	return commit_output( &json );
}

static void print_report( const options* o, const season_run* r )
{
	const int32_t S = r->chain.state_count;
	printf( "leaf     %d vertices, %d triangles after %lld optimization iterations, %d deformation levels (%.2f s)\n",
			r->leaf.vertex_count, r->leaf.triangle_count, o->optimize, r->leaf.level_count, r->leaf_seconds );
	printf( "tree     %d branch segments, %d leaves (L-system, %lld iterations)\n", r->tree.segment_count,
			r->tree.leaf_count, o->iterations );
	printf( "chain    %d states, %lld leaves, %d days, %d threads: %.3f ms per day (%.3g leaves/s)\n", S, o->leaves,
			r->days, r->threads, 1e3 * r->step_seconds / r->days, (double) o->leaves * r->days / r->step_seconds );
	printf( "day %-4d", r->days );
	for ( int32_t s = 0; s < S; ++s )
	{
		printf( " %s %.3f", r->chain.name[s], r->sampled[(size_t) r->days * S + s] );
	}
	printf( "\n         largest |sampled - exact| share over all days and states: %.2g\n", r->worst );
	printf( "wrote    %s/{distribution.csv,summary.json,tree_*.ply%s}\n", o->out,
			o->pictures ? ",season_*.png,seasons.png,leaf_levels.png,distribution.png" : "" );
}

int sere_cmd_season( int argc, char** argv )
{
	options o;
	int parsed = parse_options( argc, argv, &o );
	if ( parsed != SERE_OPTIONS_GO )
	{
		return parsed;
	}
	/* Static: the chain and the schedule hold fixed tables too large for the stack. */
	static season_run run;
	season_run* r = &run;
	memset( r, 0, sizeof( *r ) );
	int rc = read_inputs( &o, r );
	if ( rc != 0 )
	{
		return rc;
	}
	r->threads = sere_topo_bind( (int) o.threads, NULL );
	rc = grow_leaf_and_tree( &o, r );
	if ( rc != 0 )
	{
		return rc;
	}
	rc = prepare_days( &o, r );
	rc = rc != 0 ? rc : step_days( &o, r );
	rc = rc != 0 ? rc : write_distribution_csv( &o, r );
	rc = rc != 0 ? rc : write_trees( &o, r );
	rc = rc != 0 || !o.pictures ? rc : write_pictures( &o, r );
	rc = rc != 0 ? rc : write_summary( &o, r );
	if ( rc == 0 )
	{
		print_report( &o, r );
	}
	free( r->states ), free( r->exact ), free( r->sampled ), free( r->P ), free( r->counts ), free( r->snapshots );
	free( r->day_table );
	sere_tree_destroy( &r->tree );
	sere_season_leaf_destroy( &r->leaf );
	return rc;
}
