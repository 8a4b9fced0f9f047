#include "common/machine.h"

#include "common/io.h"
#include "common/topo.h"
#include "core/base.h"

#include <ctype.h>
#include <hwloc.h>
#include <omp.h>
#include <string.h>

/* The Makefile passes the commit it computed for `sere --version` (GIT_COMMIT) on this file's
 * compile line too, so both report the same build. */
#ifndef SERE_GIT_COMMIT
#define SERE_GIT_COMMIT "unknown"
#endif

#if defined( __clang__ )
#define SERE_MACHINE_COMPILER __VERSION__
#elif defined( __GNUC__ )
#define SERE_MACHINE_COMPILER "gcc " __VERSION__
#else
#define SERE_MACHINE_COMPILER "unknown"
#endif

/* Copies text without its leading and trailing white space, cut to fit size. */
static void copy_trimmed( char* out, size_t size, const char* text )
{
	while ( *text != '\0' && isspace( (unsigned char) *text ) )
	{
		++text;
	}
	size_t length = strlen( text );
	while ( length > 0 && isspace( (unsigned char) text[length - 1] ) )
	{
		--length;
	}
	if ( length >= size )
	{
		length = size - 1;
	}
	memcpy( out, text, length );
	out[length] = '\0';
}

/* The first "model name" of /proc/cpuinfo (x86 and most others); 0 when there is none. */
static int cpu_from_proc( char* out, size_t size )
{
	FILE* f = fopen( "/proc/cpuinfo", "r" );
	if ( f == NULL )
	{
		return 0;
	}
	char line[1024];
	int found = 0;
	while ( !found && fgets( line, sizeof( line ), f ) != NULL )
	{
		char* colon = strchr( line, ':' );
		if ( colon == NULL )
		{
			continue;
		}
		*colon = '\0';
		char key[64];
		copy_trimmed( key, sizeof( key ), line );
		if ( strcmp( key, "model name" ) == 0 )
		{
			copy_trimmed( out, size, colon + 1 );
			found = out[0] != '\0';
		}
	}
	fclose( f );
	return found;
}

/* hwloc's CPUModel of the first package that names one; 0 when none does. */
static int cpu_from_hwloc( hwloc_topology_t topology, char* out, size_t size )
{
	int packages = hwloc_get_nbobjs_by_type( topology, HWLOC_OBJ_PACKAGE );
	for ( int i = 0; i < packages; ++i )
	{
		hwloc_obj_t package = hwloc_get_obj_by_type( topology, HWLOC_OBJ_PACKAGE, (unsigned) i );
		const char* model = package != NULL ? hwloc_obj_get_info_by_name( package, "CPUModel" ) : NULL;
		if ( model != NULL && model[0] != '\0' )
		{
			copy_trimmed( out, size, model );
			return 1;
		}
	}
	return 0;
}

/* The core whose CPU set holds all of set, or -1: a set that is the whole machine is unbound
 * (on a one-core machine too, where binding could change nothing). */
static int core_holding( hwloc_topology_t topology, hwloc_const_cpuset_t set )
{
	if ( hwloc_bitmap_iszero( set ) || hwloc_bitmap_isequal( set, hwloc_topology_get_topology_cpuset( topology ) ) )
	{
		return -1;
	}
	int cores = hwloc_get_nbobjs_by_type( topology, HWLOC_OBJ_CORE );
	for ( int c = 0; c < cores; ++c )
	{
		hwloc_obj_t core = hwloc_get_obj_by_type( topology, HWLOC_OBJ_CORE, (unsigned) c );
		if ( core != NULL && core->cpuset != NULL && hwloc_bitmap_isincluded( set, core->cpuset ) )
		{
			return c;
		}
	}
	return -1;
}

/* The threads whose binding is asked and written: at least one, at most the table's size. */
static int team_of( int threads )
{
	return threads < 1 ? 1 : threads > SERE_MACHINE_MAX_THREADS ? SERE_MACHINE_MAX_THREADS : threads;
}

void sere_machine_read( sere_machine* machine, int threads )
{
	memset( machine, 0, sizeof( *machine ) );
	machine->simd = sere_simd_path();
	machine->threads = threads;
	machine->cores = sere_topo_cores();
	machine->version = sere_version();
	machine->commit = SERE_GIT_COMMIT;
	machine->compiler = SERE_MACHINE_COMPILER;
	int team = team_of( threads );
	for ( int i = 0; i < SERE_MACHINE_MAX_THREADS; ++i )
	{
		machine->core_of[i] = -1;
	}

	hwloc_topology_t topology = NULL;
	if ( hwloc_topology_init( &topology ) != 0 )
	{
		topology = NULL;
	}
	else if ( hwloc_topology_load( topology ) != 0 )
	{
		hwloc_topology_destroy( topology );
		topology = NULL;
	}
	if ( !cpu_from_proc( machine->cpu, sizeof( machine->cpu ) ) &&
		 ( topology == NULL || !cpu_from_hwloc( topology, machine->cpu, sizeof( machine->cpu ) ) ) )
	{
		copy_trimmed( machine->cpu, sizeof( machine->cpu ), "unknown" );
	}
	if ( topology == NULL )
	{
		return; /* nothing to ask: every thread reads as unbound */
	}
	/* Each OpenMP thread asks for its own binding: the team of this size is the one the kernels
	 * run on and that sere_topo_bind bound, thread i to core i mod cores. */
	int* core_of = machine->core_of;
#pragma omp parallel num_threads( team )
	{
		int id = omp_get_thread_num();
		hwloc_cpuset_t set = hwloc_bitmap_alloc();
		if ( set != NULL && id < team && hwloc_get_cpubind( topology, set, HWLOC_CPUBIND_THREAD ) == 0 )
		{
			core_of[id] = core_holding( topology, set );
		}
		hwloc_bitmap_free( set );
	}
	for ( int i = 0; i < team; ++i )
	{
		machine->bound |= core_of[i] >= 0;
	}
	hwloc_topology_destroy( topology );
}

const char* sere_machine_binding_text( const sere_machine* machine, char* out, size_t size )
{
	if ( size == 0 )
	{
		return out;
	}
	out[0] = '\0';
	if ( !machine->bound )
	{
		snprintf( out, size, "unbound" );
		return out;
	}
	int team = team_of( machine->threads );
	size_t used = 0;
	for ( int i = 0; i < team && used < size; ++i )
	{
		int written = machine->core_of[i] >= 0
						  ? snprintf( out + used, size - used, "%s%d", i ? "," : "", machine->core_of[i] )
						  : snprintf( out + used, size - used, "%s-", i ? "," : "" );
		if ( written < 0 )
		{
			break;
		}
		used += (size_t) written;
	}
	return out;
}

void sere_machine_write_json( FILE* f, const char* indent, const sere_machine* machine )
{
	const char* in = indent != NULL ? indent : "";
	char cpu[6 * sizeof( machine->cpu )], simd[64], version[128], commit[512], compiler[1024];
	fprintf( f, "%s\"machine\": {\n", in );
	fprintf( f, "%s  \"cpu\": \"%s\",\n", in, sere_json_escape( cpu, sizeof( cpu ), machine->cpu ) );
	fprintf( f, "%s  \"simd\": \"%s\",\n", in, sere_json_escape( simd, sizeof( simd ), machine->simd ) );
	fprintf( f, "%s  \"threads\": %d,\n", in, machine->threads );
	fprintf( f, "%s  \"binding\": ", in );
	if ( !machine->bound )
	{
		fprintf( f, "\"unbound\"" );
	}
	else
	{
		int team = team_of( machine->threads );
		fprintf( f, "[" );
		for ( int i = 0; i < team; ++i )
		{
			if ( machine->core_of[i] >= 0 )
			{
				fprintf( f, "%s%d", i ? ", " : "", machine->core_of[i] );
			}
			else
			{
				fprintf( f, "%snull", i ? ", " : "" );
			}
		}
		fprintf( f, "]" );
	}
	fprintf( f, ",\n%s  \"cores\": %d,\n", in, machine->cores );
	fprintf( f, "%s  \"version\": \"%s\",\n", in, sere_json_escape( version, sizeof( version ), machine->version ) );
	fprintf( f, "%s  \"commit\": \"%s\",\n", in, sere_json_escape( commit, sizeof( commit ), machine->commit ) );
	fprintf( f, "%s  \"compiler\": \"%s\"\n", in, sere_json_escape( compiler, sizeof( compiler ), machine->compiler ) );
	fprintf( f, "%s}", in );
}

void sere_machine_json( FILE* f, const char* indent, int threads )
{
	sere_machine machine;
	sere_machine_read( &machine, threads );
	sere_machine_write_json( f, indent, &machine );
}
