/* sere litter — private to the cmd_litter*.c files: a leaf's outcome and the processes that
 * share the leaves (issue #21). */
#pragma once

#include <stdint.h>

/* A leaf's outcome: dried now, reused from an earlier run, or failed with a reason. */
typedef enum litter_state
{
	LITTER_FAILED,
	LITTER_DRIED,
	LITTER_RESUMED
} litter_state;

typedef struct litter_result
{
	litter_state state;
	int rank;
	int desiccated; /* it dried to the end (a layer ran dry) before the frame cap */
	int32_t vertices, triangles;
	long frames;
	double ms;
	char error[4400];
} litter_result;

/* The processes sharing the leaves: MPI's ranks under mpirun (one alone without it), and
 * those of them on this machine, which share its cores. Without MPI, one process. */
typedef struct litter_world
{
	int rank, size, local_rank, local_size;
	int mpi; /* MPI was started (under a launcher): every rank must take part in its calls */
} litter_world;

/* Starts MPI when a launcher started this process; 0, or -1 when MPI did not start. */
int litter_world_init( litter_world* w );

/* Ends the run on every rank with the worst of their statuses, so that a leaf failed on any
 * rank makes every rank's exit code non-zero. */
int litter_world_finish( const litter_world* w, int status );

/* Out of memory after MPI started: the other ranks would wait for this one forever. 1. */
int litter_world_abort( const litter_world* w );

void litter_world_barrier( const litter_world* w );

/* Rank 0 gets every rank's results (each rank's leaves in the order of order[] that owner[]
 * gives it) and every rank's drying wall time; the other ranks keep their own. Its return also
 * tells rank 0 that every leaf file is written, as each rank sends only after writing its own. */
int litter_world_gather( const litter_world* w, litter_result* results, const long* order, const int* owner,
						 long leaves, double wall_ms, double* rank_wall_ms );
