/* sere harness — machine topology and thread binding with hwloc (kernels never see hwloc). */
#pragma once

#include <stdio.h>

/* Sets the OpenMP thread count (0 = one per core) and binds thread i to core i (round-robin
 * over cores, one PU each) so timings do not wander between cores. Returns the thread count
 * used; writes one line per thread to log when log is not NULL. */
int sere_topo_bind( int threads, FILE* log );

/* sere_topo_bind with thread i bound to core first_core + i (mod cores): processes sharing a
 * machine (MPI ranks) pass disjoint first cores so that their threads do not pile onto core 0. */
int sere_topo_bind_from( int threads, int first_core, FILE* log );

/* Prints packages, cores, PUs and caches as hwloc sees them. */
void sere_topo_print( FILE* f );

/* Number of physical cores (at least 1). */
int sere_topo_cores( void );
