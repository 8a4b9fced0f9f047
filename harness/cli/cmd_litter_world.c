/* sere litter — the processes that share the leaves (MPI's ranks under a launcher, one process
 * without): start, barrier, gathering the results on rank 0, and the end of the run. */
#define _POSIX_C_SOURCE 200809L
#include "cli/cmd_litter_shared.h"

#include <stdlib.h>

#ifdef SERE_MPI
#include <mpi.h>
#endif

#ifdef SERE_MPI
/* Whether an MPI launcher started this process: Open MPI's mpirun sets OMPI_COMM_WORLD_SIZE,
 * PMIx launchers (mpirun, srun --mpi=pmix) PMIX_RANK, PMI-1/2 ones (srun, MPICH's hydra)
 * PMI_RANK. Started alone, the command runs as one process without MPI: Open MPI's singleton
 * start would fork a daemon only to learn that there is one rank. */
static int litter_launched( void )
{
	return getenv( "OMPI_COMM_WORLD_SIZE" ) != NULL || getenv( "PMIX_RANK" ) != NULL || getenv( "PMI_RANK" ) != NULL;
}
#endif

int litter_world_init( litter_world* w )
{
	*w = ( litter_world ){ 0, 1, 0, 1, 0 };
#ifdef SERE_MPI
	if ( !litter_launched() )
	{
		return 0;
	}
	w->mpi = 1;
	/* only the main thread calls MPI; the OpenMP threads only dry leaves */
	int provided;
	if ( MPI_Init_thread( NULL, NULL, MPI_THREAD_FUNNELED, &provided ) != MPI_SUCCESS )
	{
		return -1;
	}
	MPI_Comm_rank( MPI_COMM_WORLD, &w->rank );
	MPI_Comm_size( MPI_COMM_WORLD, &w->size );
	MPI_Comm local;
	MPI_Comm_split_type( MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, 0, MPI_INFO_NULL, &local );
	MPI_Comm_rank( local, &w->local_rank );
	MPI_Comm_size( local, &w->local_size );
	MPI_Comm_free( &local );
#endif
	return 0;
}

/* Ends the run on every rank with the worst of their statuses, so that a leaf failed on any
 * rank makes every rank's exit code non-zero. */
int litter_world_finish( const litter_world* w, int status )
{
#ifdef SERE_MPI
	if ( !w->mpi )
	{
		return status;
	}
	int worst = status;
	MPI_Allreduce( &status, &worst, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD );
	MPI_Finalize();
	return worst;
#else
	(void) w;
	return status;
#endif
}

/* Out of memory after MPI started: the other ranks would wait for this one forever. */
int litter_world_abort( const litter_world* w )
{
#ifdef SERE_MPI
	if ( w->mpi )
	{
		MPI_Abort( MPI_COMM_WORLD, 1 );
	}
#else
	(void) w;
#endif
	return 1;
}

void litter_world_barrier( const litter_world* w )
{
#ifdef SERE_MPI
	if ( w->mpi )
	{
		MPI_Barrier( MPI_COMM_WORLD );
	}
#else
	(void) w;
#endif
}

/* Rank 0 gets every rank's results (each rank's leaves in the order of order[] that owner[]
 * gives it) and every rank's drying wall time; the other ranks keep their own. Its return also
 * tells rank 0 that every leaf file is written, as each rank sends only after writing its own. */
int litter_world_gather( const litter_world* w, litter_result* results, const long* order, const int* owner,
						 long leaves, double wall_ms, double* rank_wall_ms )
{
	rank_wall_ms[0] = wall_ms;
	if ( w->size == 1 )
	{
		return 0;
	}
#ifdef SERE_MPI
	long mine = 0;
	for ( long k = 0; k < leaves; ++k )
	{
		mine += owner[order[k]] == w->rank;
	}
	litter_result* packed = malloc( sizeof( litter_result ) * (size_t) ( mine > 0 ? mine : 1 ) );
	int* counts = malloc( sizeof( int ) * (size_t) w->size );
	int* displs = malloc( sizeof( int ) * (size_t) w->size );
	litter_result* all = w->rank == 0 ? malloc( sizeof( litter_result ) * (size_t) leaves ) : NULL;
	if ( packed == NULL || counts == NULL || displs == NULL || ( w->rank == 0 && all == NULL ) )
	{
		return -1;
	}
	long at = 0;
	for ( long k = 0; k < leaves; ++k )
	{
		if ( owner[order[k]] == w->rank )
		{
			packed[at++] = results[order[k]];
		}
	}
	for ( int r = 0; r < w->size; ++r )
	{
		counts[r] = 0;
	}
	for ( long k = 0; k < leaves; ++k )
	{
		counts[owner[k]] += (int) sizeof( litter_result );
	}
	for ( int r = 0, sum = 0; r < w->size; sum += counts[r], ++r )
	{
		displs[r] = sum;
	}
	MPI_Gatherv( packed, (int) ( sizeof( litter_result ) * (size_t) mine ), MPI_BYTE, all, counts, displs, MPI_BYTE, 0,
				 MPI_COMM_WORLD );
	MPI_Gather( &wall_ms, 1, MPI_DOUBLE, rank_wall_ms, 1, MPI_DOUBLE, 0, MPI_COMM_WORLD );
	if ( w->rank == 0 )
	{
		/* each rank's block holds its leaves in the order it was given them */
		for ( int r = 0; r < w->size; ++r )
		{
			long next = displs[r] / (long) sizeof( litter_result );
			for ( long k = 0; k < leaves; ++k )
			{
				if ( owner[order[k]] == r )
				{
					results[order[k]] = all[next++];
				}
			}
		}
	}
	free( all ), free( displs ), free( counts ), free( packed );
#else
	/* one process holds every result already */
	(void) results, (void) order, (void) owner, (void) leaves;
#endif
	return 0;
}
