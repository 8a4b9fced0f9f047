#include "cli/cmd_leaf.h"
#include "cli/commands.h"
#include "cli/options.h"
#include "common/machine.h"
#include "common/topo.h"
#include "drying/leaf.h"
#include "read/build.h"

#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Table 1 of the paper (Core i5 2.67 GHz, one thread, C++), ms per frame. */
typedef struct table1_row
{
	const char* leaf;
	const char* path;
	const char* preset;
	long long particles, springs;
	double osmosis, dynamics, collisions, total;
} table1_row;

static const table1_row rows[3] = {
	{ "maple", "data/leaves/maple.leaf", "maple-green", 13197, 51102, 155.65, 1157.19, 24.28, 1337.03 },
	{ "plane tree", "data/leaves/plane.leaf", "plane-tree", 15069, 59550, 81.69, 1492.01, 29.03, 1602.73 },
	{ "wisteria", "data/leaves/wisteria.leaf", "wisteria", 12750, 50436, 16.26, 1499.41, 23.16, 1538.83 },
};

/* The heading: the machine facts (JSON) or the column titles with the run's machine line. */
static void table1_print_head( int json, int bound, long long frames, long long rounds )
{
	if ( json )
	{
		printf( "{\n" );
		sere_machine_json( stdout, "  ", bound );
		printf( ",\n  \"leaves\": [" );
		return;
	}
	printf( "Table 1, ms per frame (paper: Core i5 2.67 GHz, 1 thread; ours: %d threads, mean of %lld frames", bound,
			frames );
	if ( rounds > 1 )
	{
		printf( ", median of %lld rounds", rounds );
	}
	printf( ")\n" );
	sere_machine machine;
	char binding[1024];
	sere_machine_read( &machine, bound );
	sere_machine_binding_text( &machine, binding, sizeof( binding ) );
	printf( "ours: %s, %s, threads %s%s, sere %s (commit %s), %s\n\n", machine.cpu, machine.simd,
			machine.bound ? "on cores " : "", binding, machine.version, machine.commit, machine.compiler );
	printf( "%-11s %9s %8s | %17s | %17s | %17s | %17s | %7s | %6s | %11s | %s", "leaf", "particles", "springs",
			"osmotic flow", "dynamics", "collisions", "total", "ratio", "sweeps", "CG it. T V", "PBD cap hits" );
	if ( rounds > 1 )
	{
		printf( " | ratio range\n" );
	}
	else
	{
		printf( "\n" );
	}
}

/* One leaf's mean ms per frame over one round, and how often PBD hit its cap or stalled. */
typedef struct table1_times
{
	double osmosis, dynamics, collisions, total;
	double sweeps, cg_t, cg_v; /* per frame: PBD sweeps, CG iterations of each layer */
	long long cap_hits, stalls;
	int particles, springs; /* of the leaf as built */
} table1_times;

/* A leaf's rounds: their times in the order run, and each column's median over them. */
#define TABLE1_MAX_ROUNDS 1000

typedef struct table1_rounds
{
	table1_times round[TABLE1_MAX_ROUNDS];
	int count;
} table1_rounds;

static int table1_compare( const void* a, const void* b )
{
	double x = *(const double*) a, y = *(const double*) b;
	return ( x > y ) - ( x < y );
}

/* The median over the rounds of the double at `offset` in table1_times (the mean of the middle
 * two for an even count), from a sorted copy. */
static double table1_median( const table1_rounds* r, size_t offset )
{
	double values[TABLE1_MAX_ROUNDS];
	for ( int k = 0; k < r->count; ++k )
	{
		memcpy( values + k, (const char*) ( r->round + k ) + offset, sizeof( double ) );
	}
	qsort( values, (size_t) r->count, sizeof( double ), table1_compare );
	int m = r->count / 2;
	return r->count % 2 == 1 ? values[m] : 0.5 * ( values[m - 1] + values[m] );
}

/* Each timed column's median over the rounds; the counts are the same in every round. */
static table1_times table1_medians( const table1_rounds* r )
{
	table1_times t = r->round[0];
	t.osmosis = table1_median( r, offsetof( table1_times, osmosis ) );
	t.dynamics = table1_median( r, offsetof( table1_times, dynamics ) );
	t.collisions = table1_median( r, offsetof( table1_times, collisions ) );
	t.total = table1_median( r, offsetof( table1_times, total ) );
	return t;
}

static void table1_print_row( int json, int comma, const table1_row* row, const sere_sim_params* params,
							  const table1_rounds* r, long long frames, int bound )
{
	const table1_times median = table1_medians( r );
	const table1_times* t = &median;
	double fastest = r->round[0].total, slowest = r->round[0].total;
	for ( int k = 1; k < r->count; ++k )
	{
		fastest = r->round[k].total < fastest ? r->round[k].total : fastest;
		slowest = r->round[k].total > slowest ? r->round[k].total : slowest;
	}
	if ( json )
	{
		printf( "%s{\"leaf\": \"%s\", \"particles\": %d, \"springs\": %d, \"osmosis_ms\": %.4f, \"dynamics_ms\": %.4f, "
				"\"collisions_ms\": %.4f, \"total_ms\": %.4f, \"paper_osmosis_ms\": %.2f, \"paper_dynamics_ms\": %.2f, "
				"\"paper_collisions_ms\": %.2f, \"paper_total_ms\": %.2f, \"pbd_tolerance\": %g, \"pbd_cap\": %d, "
				"\"pbd_cap_hits\": %lld, \"pbd_stall\": %g, \"pbd_stalls\": %lld, \"compliance\": %g, "
				"\"pbd_sweeps_per_frame\": %.2f, \"cg_iterations_t_per_frame\": %.2f, "
				"\"cg_iterations_v_per_frame\": %.2f, \"frames\": %lld, \"threads\": %d, \"rounds\": %d, "
				"\"round_total_ms\": [",
				comma ? ", " : "", row->leaf, t->particles, t->springs, t->osmosis, t->dynamics, t->collisions,
				t->total, row->osmosis, row->dynamics, row->collisions, row->total, params->leaf.pbd.tolerance,
				params->leaf.pbd.max_iterations, t->cap_hits, params->leaf.pbd.stall, t->stalls,
				params->leaf.pbd.compliance, t->sweeps, t->cg_t, t->cg_v, frames, bound, r->count );
		for ( int k = 0; k < r->count; ++k )
		{
			printf( "%s%.4f", k > 0 ? ", " : "", r->round[k].total );
		}
		printf( "]}" );
		return;
	}
	printf( "%-11s %9d %8d | %7.2f / %7.2f | %7.2f / %7.2f | %7.2f / %7.2f | %7.2f / %7.2f | %6.1fx | %6.1f | "
			"%5.1f %5.1f | %lld/%lld",
			row->leaf, t->particles, t->springs, t->osmosis, row->osmosis, t->dynamics, row->dynamics, t->collisions,
			row->collisions, t->total, row->total, row->total / t->total, t->sweeps, t->cg_t, t->cg_v, t->cap_hits,
			frames );
	if ( params->leaf.pbd.stall > 0.0f )
	{
		printf( ", stalled %lld/%lld", t->stalls, frames );
	}
	if ( r->count > 1 )
	{
		printf( " | %.1f-%.1fx", row->total / slowest, row->total / fastest );
	}
	printf( "\n" );
}

/* Builds row k's leaf at its Table 1 counts with its preset (*params) and dries it for `frames`
 * into *t; 1 on an error (already reported). */
static int table1_leaf( int k, const sere_option_list* sets, long long frames, int bound, sere_sim_params* params_out,
						table1_times* out )
{
	const table1_row* row = rows + k;
	char name[128];
	sere_sim_params params = sere_sim_params_default();
	params.leaf.step_residual = 0; /* a measure beside the frame, not part of it (--set can ask for it) */
	if ( !command_params_apply( "table1", &params, row->preset, sets ) )
	{
		return 1;
	}
	*params_out = params;
	sere_model model;
	sere_build_report report;
	if ( !command_model_build( "table1", row->path, row->particles, row->springs, 0, &params, &model, &report, name,
							   sizeof( name ) ) )
	{
		return 1;
	}
	sere_leaf_sim* sim = NULL;
	sere_status status = sere_leaf_create( &model, &sim );
	status = status == SERE_OK ? sere_leaf_set_threads( sim, bound ) : status;
	table1_times t = { 0 };
	sere_leaf_stats stats;
	long long frame = 0;
	for ( long long f = 0; f < frames && status == SERE_OK; ++f )
	{
		frame = f + 1;
		status = sere_leaf_step( sim, &params.leaf, &stats );
		t.osmosis += stats.osmosis_ms, t.dynamics += stats.dynamics_ms;
		t.collisions += stats.collisions_ms, t.total += stats.total_ms;
		t.sweeps += stats.pbd_iterations, t.cg_t += stats.cg_iterations_t, t.cg_v += stats.cg_iterations_v;
		t.cap_hits += stats.pbd_hit_cap;
		t.stalls += stats.pbd_stalled;
	}
	t.particles = model.p.count, t.springs = model.s.count;
	sere_leaf_destroy( sim );
	sere_model_destroy( &model );
	if ( status != SERE_OK )
	{
		char why[256];
		command_step_error( &params, status, why, sizeof( why ) );
		if ( frame > 0 )
		{
			fprintf( stderr, "sere table1: %s: frame %lld: %s\n", row->leaf, frame, why );
		}
		else
		{
			fprintf( stderr, "sere table1: %s: %s\n", row->leaf, why );
		}
		return 1;
	}
	t.osmosis /= frames, t.dynamics /= frames, t.collisions /= frames, t.total /= frames;
	t.sweeps /= frames, t.cg_t /= frames, t.cg_v /= frames;
	*out = t;
	return 0;
}

/* The closing bracket (JSON) or the note on how a frame's projection stops. */
static void table1_print_tail( int json, const sere_option_list* sets )
{
	if ( json )
	{
		printf( "]\n}\n" );
		return;
	}
	printf( "\neach cell: ours / paper. A frame's step is the descent of the XPBD step's energy (the default),\n"
			"which stops when a sweep moves no particle farther than descent_tolerance of a spring (or the\n"
			"rounding of the coordinates), or at its max_iterations sweeps (a cap hit); with --set descent=0\n"
			"the XPBD projection, stopped at max |C + alpha~ lambda|/l < strain_tolerance, and with\n"
			"--set compliance=0 the paper's PBD, stopped at max |C/l| (the rule behind the paper's\n"
			"Table 1). sweeps: sweeps a frame; CG it.: the osmosis CG's iterations a frame on the\n"
			"triangle (T) and Voronoi (V) layer." );
	if ( sets->count > 0 )
	{
		printf( " Overrides:" );
		for ( int k = 0; k < sets->count; ++k )
		{
			printf( " %s", sets->items[k] );
		}
	}
	printf( "\n" );
}

static void table1_help( void )
{
	printf( "usage: sere table1 [--frames N] [--threads T] [--leaf all|maple|plane|wisteria] [--set key=value]...\n"
			"                   [--rounds R] [--json]\n\n"
			"Builds the three Table 1 leaves with their exact particle and spring counts, dries each for N\n"
			"frames (default 200) with its Table 2 preset, and prints our Osmotic flow / Dynamics / Collisions /\n"
			"Total ms per frame beside the paper's, with the ratio paper / ours. Threads are bound to cores\n"
			"with hwloc (T = 0: one per core). --set overrides a parameter of all three presets (keys as in\n"
			"sere run --help), e.g. --set pbd_stall=0.01 for the stall-aware PBD stop. --leaf runs one of\n"
			"the three alone (for a profiler).\n\n"
			"--rounds R (default 1) dries each leaf R times, the leaves taking turns (round 1 of every leaf,\n"
			"then round 2, ...), so that a busy spell on a shared machine slows one round of each rather than\n"
			"every round of one. Each cell is then the median over the rounds, and the last column the\n"
			"ratio's range over them.\n\n"
			"--json prints one object: \"machine\" (CPU model, SIMD path, threads and the core each is bound\n"
			"to, sere version, commit, compiler) and \"leaves\", one entry per leaf, with \"rounds\" and each\n"
			"round's total in \"round_total_ms\".\n" );
}

int sere_cmd_table1( int argc, char** argv )
{
	long long frames = 200, threads = 0, rounds = 1;
	int json = 0, leaf = 0;
	sere_option_list sets = { .count = 0 };
	static const char* const leaves[] = { "all", "maple", "plane", "wisteria", NULL };
	const sere_option options[] = {
		{ "--frames", SERE_OPTION_COUNT, &frames, 1, 1000000, NULL },
		{ "--leaf", SERE_OPTION_CHOICE, &leaf, 0, 0, leaves },
		{ "--rounds", SERE_OPTION_COUNT, &rounds, 1, TABLE1_MAX_ROUNDS, NULL },
		sere_option_threads( &threads ),
		sere_option_sets( &sets ),
		sere_option_json( &json ),
	};
	int code = sere_options_read( "table1", argc, argv, options, sizeof( options ) / sizeof( options[0] ), NULL, NULL,
								  table1_help );
	if ( code != SERE_OPTIONS_GO )
	{
		return code;
	}
	int bound = sere_topo_bind( (int) threads, NULL );
	table1_rounds* runs = calloc( 3, sizeof( table1_rounds ) );
	sere_sim_params params[3];
	if ( runs == NULL )
	{
		fprintf( stderr, "sere table1: out of memory\n" );
		return 1;
	}
	int code_out = 0;
	for ( int r = 0; r < rounds && code_out == 0; ++r )
	{
		if ( rounds > 1 )
		{
			fprintf( stderr, "sere table1: round %d of %lld\n", r + 1, rounds );
		}
		for ( int k = 0; k < 3 && code_out == 0; ++k )
		{
			if ( leaf == 0 || leaf == k + 1 )
			{
				code_out = table1_leaf( k, &sets, frames, bound, params + k, runs[k].round + r );
				runs[k].count = r + 1;
			}
		}
	}
	if ( code_out == 0 )
	{
		table1_print_head( json, bound, frames, rounds );
		for ( int k = 0, printed = 0; k < 3; ++k )
		{
			if ( leaf == 0 || leaf == k + 1 )
			{
				table1_print_row( json, printed++, rows + k, params + k, runs + k, frames, bound );
			}
		}
		table1_print_tail( json, &sets );
	}
	free( runs );
	return code_out;
}
