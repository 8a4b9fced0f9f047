#include "common/topo.h"

#include <hwloc.h>
#include <omp.h>

static hwloc_topology_t load_topology( void )
{
	hwloc_topology_t topology;
	if ( hwloc_topology_init( &topology ) != 0 )
	{
		return NULL;
	}
	if ( hwloc_topology_load( topology ) != 0 )
	{
		hwloc_topology_destroy( topology );
		return NULL;
	}
	return topology;
}

int sere_topo_cores( void )
{
	hwloc_topology_t topology = load_topology();
	if ( topology == NULL )
	{
		return 1;
	}
	int cores = hwloc_get_nbobjs_by_type( topology, HWLOC_OBJ_CORE );
	hwloc_topology_destroy( topology );
	return cores > 0 ? cores : 1;
}

int sere_topo_bind( int threads, FILE* log )
{
	return sere_topo_bind_from( threads, 0, log );
}

int sere_topo_bind_from( int threads, int first_core, FILE* log )
{
	hwloc_topology_t topology = load_topology();
	int cores = topology ? hwloc_get_nbobjs_by_type( topology, HWLOC_OBJ_CORE ) : 0;
	if ( threads <= 0 )
	{
		threads = cores > 0 ? cores : 1;
	}
	omp_set_num_threads( threads );
	if ( topology == NULL || cores <= 0 )
	{
		if ( log != NULL )
		{
			fprintf( log, "hwloc could not read the topology; %d threads left unbound\n", threads );
		}
		if ( topology != NULL )
		{
			hwloc_topology_destroy( topology );
		}
		return threads;
	}
	int bound[256] = { 0 };
	int pu_of[256] = { 0 };
#pragma omp parallel num_threads( threads )
	{
		int id = omp_get_thread_num();
		hwloc_obj_t core =
			hwloc_get_obj_by_type( topology, HWLOC_OBJ_CORE, (unsigned) ( ( first_core + id ) % cores ) );
		if ( core != NULL && core->cpuset != NULL && id < 256 )
		{
			hwloc_cpuset_t set = hwloc_bitmap_dup( core->cpuset );
			hwloc_bitmap_singlify( set ); /* one PU of the core: no migration between hyperthreads */
			bound[id] = hwloc_set_cpubind( topology, set, HWLOC_CPUBIND_THREAD ) == 0;
			pu_of[id] = hwloc_bitmap_first( set );
			hwloc_bitmap_free( set );
		}
	}
	if ( log != NULL )
	{
		for ( int id = 0; id < threads && id < 256; ++id )
		{
			fprintf( log, "thread %d -> core %d (PU %d)%s\n", id, ( first_core + id ) % cores, pu_of[id],
					 bound[id] ? "" : " [binding refused]" );
		}
	}
	hwloc_topology_destroy( topology );
	return threads;
}

void sere_topo_print( FILE* f )
{
	hwloc_topology_t topology = load_topology();
	if ( topology == NULL )
	{
		fprintf( f, "hwloc could not read the topology\n" );
		return;
	}
	int depth = hwloc_topology_get_depth( topology );
	for ( int d = 0; d < depth; ++d )
	{
		int count = hwloc_get_nbobjs_by_depth( topology, (unsigned) d );
		for ( int i = 0; i < count; ++i )
		{
			hwloc_obj_t obj = hwloc_get_obj_by_depth( topology, (unsigned) d, (unsigned) i );
			char type[64], attr[256];
			hwloc_obj_type_snprintf( type, sizeof( type ), obj, 0 );
			hwloc_obj_attr_snprintf( attr, sizeof( attr ), obj, " ", 0 );
			fprintf( f, "%*s%s #%u%s%s%s\n", 2 * d, "", type, obj->logical_index, attr[0] ? " (" : "", attr,
					 attr[0] ? ")" : "" );
		}
	}
	hwloc_topology_destroy( topology );
}
