/* scripts/bench-table.py, the README's kernel table from one sere-bench run: it must quote the
 * medians over repetitions (not the means, not a single repetition), divide a many-sweep call into
 * sweeps, take each ratio within the run, show what the run lacks as "–", and refuse a file that
 * is not a benchmark run. The runs here are written by hand in Google Benchmark's JSON format
 * (--benchmark_out_format=json with --benchmark_repetitions and aggregates), with numbers chosen
 * so that each wrong reading gives a different cell. That every benchmark the table names exists
 * in sere-bench is checked where sere-bench is built (make bench-table-check, run by CI). */
#define _DEFAULT_SOURCE
#include "fixture.h"

#include <criterion/criterion.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* A run of four benchmarks: the PBD sweep and its floor at 1 thread with repetitions (mean,
 * median and stddev aggregates, the median differing from the mean), the reference twin as one
 * run in nanoseconds, and the sweep at 2 threads with no floor. */
static const char run_json[] =
	"{\"context\": {\"date\": \"2026-11-28T03:00:00+00:00\", \"cpu\": \"Test CPU\", \"simd\": \"AVX-512\",\n"
	"  \"commit\": \"abc123\", \"compiler\": \"gcc 12.2.0\", \"sere_version\": \"0.1.0\", \"load_avg\": [0.5]},\n"
	" \"benchmarks\": [\n"
	"  {\"name\": \"BM_PBDColored/threads:1/sweeps:200/real_time\", \"run_name\": "
	"\"BM_PBDColored/threads:1/sweeps:200/real_time\", \"run_type\": \"iteration\", \"real_time\": 99999.0, "
	"\"time_unit\": \"us\"},\n"
	"  {\"name\": \"BM_PBDColored/threads:1/sweeps:200/real_time_mean\", \"run_name\": "
	"\"BM_PBDColored/threads:1/sweeps:200/real_time\", \"run_type\": \"aggregate\", \"aggregate_name\": \"mean\", "
	"\"real_time\": 21000.0, \"time_unit\": \"us\"},\n"
	"  {\"name\": \"BM_PBDColored/threads:1/sweeps:200/real_time_median\", \"run_name\": "
	"\"BM_PBDColored/threads:1/sweeps:200/real_time\", \"run_type\": \"aggregate\", \"aggregate_name\": \"median\", "
	"\"real_time\": 20000.0, \"time_unit\": \"us\"},\n"
	"  {\"name\": \"BM_PBDColored/threads:1/sweeps:200/real_time_stddev\", \"run_name\": "
	"\"BM_PBDColored/threads:1/sweeps:200/real_time\", \"run_type\": \"aggregate\", \"aggregate_name\": \"stddev\", "
	"\"real_time\": 300.0, \"time_unit\": \"us\"},\n"
	"  {\"name\": \"BM_PBDFloor/threads:1/sweeps:200/real_time_median\", \"run_name\": "
	"\"BM_PBDFloor/threads:1/sweeps:200/real_time\", \"run_type\": \"aggregate\", \"aggregate_name\": \"median\", "
	"\"real_time\": 16.0, \"time_unit\": \"ms\"},\n"
	"  {\"name\": \"BM_PBDReference\", \"run_name\": \"BM_PBDReference\", \"run_type\": \"iteration\", "
	"\"real_time\": 500000.0, \"time_unit\": \"ns\"},\n"
	"  {\"name\": \"BM_PBDColored/threads:2/sweeps:200/real_time\", \"run_name\": "
	"\"BM_PBDColored/threads:2/sweeps:200/real_time\", \"run_type\": \"iteration\", \"real_time\": 12000.0, "
	"\"time_unit\": \"us\"}\n"
	" ]}\n";

/* Writes text to dir/name; the path into path. */
static void write_file( const char* dir, const char* name, const char* text, char* path, size_t path_size )
{
	snprintf( path, path_size, "%s/%s", dir, name );
	FILE* f = fopen( path, "w" );
	cr_assert_not_null( f, "cannot write %s", path );
	cr_assert_eq( fputs( text, f ) >= 0, 1 );
	cr_assert_eq( fclose( f ), 0 );
}

/* The script's stdout and stderr for args; its exit status. */
static int table_of( const char* args, char* out, size_t out_size )
{
	char command[1024];
	snprintf( command, sizeof( command ), "python3 scripts/bench-table.py %s 2>&1", args );
	return sere_test_shell( command, out, out_size );
}

/* The line of the table whose first cell starts with kernel, cut at its newline. */
static void row_of( const char* table, const char* kernel, char* line, size_t line_size )
{
	char key[256];
	snprintf( key, sizeof( key ), "| %s", kernel );
	const char* at = strstr( table, key );
	cr_assert_not_null( at, "no row for %s in:\n%s", kernel, table );
	size_t length = strcspn( at, "\n" );
	cr_assert_lt( length, line_size );
	memcpy( line, at, length );
	line[length] = '\0';
}

Test( bench_table, quotes_medians_per_sweep_and_ratios_within_the_run )
{
	char* dir = sere_test_scratch( "benchtable" );
	char path[256], out[32768], line[2048];
	write_file( dir, "run.json", run_json, path, sizeof( path ) );
	cr_assert_eq( table_of( path, out, sizeof( out ) ), 0, "%s", out );
	row_of( out, "PBD sweep", line, sizeof( line ) );
	/* The median 20000 µs over 200 sweeps: 100 µs a sweep (the mean would give 105, the single
	 * repetition 500); the floor 16 ms / 200 = 80 µs; 100/80 = 1.25 exactly in binary. */
	cr_expect_not_null( strstr( line, "| 100 µs | 80 µs | 1.25× |" ), "1-thread cells: %s", line );
	/* 2 threads: 12000/200 = 60 µs, no floor in the run. */
	cr_expect_not_null( strstr( line, "| 60 µs | – | – |" ), "2-thread cells: %s", line );
	/* The twin runs one sweep an iteration: 500000 ns = 500 µs, ours 100/500 = 0.20 of it. */
	cr_expect_not_null( strstr( line, "AoS reference: 500 µs (0.20× ours/peer)" ), "peer cell: %s", line );
	/* The machine the run names heads the table. */
	cr_expect_not_null( strstr( out, "commit abc123" ), "%s", out );
	cr_expect_not_null( strstr( out, "Test CPU, AVX-512" ), "%s", out );
	/* A kernel the run lacks keeps its row, every time "–". */
	row_of( out, "XPBD sweep", line, sizeof( line ) );
	cr_expect_not_null( strstr( line, "| – | – | – | – | – | – |" ), "absent kernel: %s", line );
	sere_test_scratch_remove( dir );
}

Test( bench_table, compares_two_builds_at_one_thread )
{
	char* dir = sere_test_scratch( "benchtable" );
	char after[256], before[256], out[32768], line[2048], args[600];
	write_file( dir, "after.json", run_json, after, sizeof( after ) );
	/* the build before: the same run with the 1-thread sweep's median at 25000 µs */
	char* slower = strdup( run_json );
	char* median = strstr( slower, "\"real_time\": 20000.0" );
	cr_assert_not_null( median );
	memcpy( median, "\"real_time\": 25000.0", strlen( "\"real_time\": 25000.0" ) );
	write_file( dir, "before.json", slower, before, sizeof( before ) );
	free( slower );
	snprintf( args, sizeof( args ), "%s --before %s", after, before );
	cr_assert_eq( table_of( args, out, sizeof( out ) ), 0, "%s", out );
	cr_expect_not_null( strstr( out, "this build / before, 1 t" ), "%s", out );
	row_of( out, "PBD sweep", line, sizeof( line ) );
	/* 100 µs against 125 µs a sweep */
	cr_expect_not_null( strstr( line, "| 0.80× |" ), "%s", line );
	sere_test_scratch_remove( dir );
}

Test( bench_table, refuses_a_file_that_is_not_a_run )
{
	char* dir = sere_test_scratch( "benchtable" );
	char path[256], out[4096];
	write_file( dir, "notes.txt", "maple 1.2 ms\n", path, sizeof( path ) );
	cr_expect_neq( table_of( path, out, sizeof( out ) ), 0, "a text file made a table:\n%s", out );
	cr_expect_not_null( strstr( out, path ), "the error does not name the file: %s", out );
	/* valid JSON, but a run of none of the table's benchmarks */
	write_file( dir, "other.json", "{\"benchmarks\": [{\"run_name\": \"BM_Other\", \"real_time\": 1.0}]}\n", path,
				sizeof( path ) );
	cr_expect_neq( table_of( path, out, sizeof( out ) ), 0, "a run of other benchmarks made a table:\n%s", out );
	cr_expect_not_null( strstr( out, "none of the table's benchmarks" ), "%s", out );
	sere_test_scratch_remove( dir );
}
