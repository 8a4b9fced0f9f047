/* sere — private to the kernels (not installed, not part of the API): how many threads a
 * parallel region should use when other processes keep some of this process's cores busy.
 *
 * Issue 19: with one of two cores taken by another process, a 2-thread kernel ran 6–20× slower
 * than 1 thread. Every barrier waits for the thread that shares its core with the other
 * process, and that thread runs only in its share of time slices (milliseconds), while a
 * barrier comes every few tens of µs. Waiting passively (OMP_WAIT_POLICY=passive, or a nap
 * after a bounded spin as pbd.c does) lets the scheduler move the late thread to the core the
 * waiting one left, which brings 2 threads back near the 1-thread time (0.8–1.2× in the
 * issue), but it is no speed-up: the process has one core, and pays wake-ups and migrations
 * besides; and passive waiting costs a futex call per barrier on a quiet machine. So before
 * each parallel region the kernels ask sere_team for a thread count: the caller's (the count
 * set on the kernel's object or passed to it, base.h), capped at the cores other processes leave free, as last
 * measured. (An OMP_WAIT_POLICY default set by sere's own main would not reach users, who call the kernels from their
 * own programs; libgomp reads it once, at start-up.)
 *
 * The measure: every SERE_TEAM_INTERVAL seconds (at most; only when a kernel is called), the
 * busy time of the CPUs this process may run on (/proc/stat: user, system, irq, softirq and
 * steal, and nice when this process is itself niced) minus this process's own CPU time, over
 * the wall time since the previous sample, is the number of cores other processes used. A core
 * counts as taken when they used SERE_TEAM_TAKEN of one or more: a process sharing a core
 * with one of our threads gets half of it, so the threshold must sit below one half. Processes
 * at a higher nice level than ours do not count (a nice-19 fuzzer yields its core to us within
 * a wake-up). Results do not depend on the thread count (the kernels' determinism contract),
 * so the count may change from one call to the next.
 *
 * The first decision comes SERE_TEAM_FIRST_INTERVAL after the first call; until then a region
 * runs with the caller's count. Long calls re-ask between rounds (the CG solve does).
 * The sample costs an open and read of /proc/stat (tens of µs) four times a second at most;
 * a call otherwise pays one clock read and an atomic load. SERE_ADAPTIVE_THREADS=0 in the
 * environment turns the cap off (every region then uses omp_get_max_threads()); so does a
 * system without /proc/stat. State is per translation unit: each kernel file samples for
 * itself. */
#pragma once

#ifndef _GNU_SOURCE
#error "define _GNU_SOURCE before the first include (sched_getaffinity, CPU_ISSET)"
#endif

#include "core/base.h"

#include <fcntl.h>
#include <omp.h>
#include <sched.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <time.h>
#include <unistd.h>

#define SERE_TEAM_INTERVAL 0.25
/* The first window after a process's first call: long enough for /proc/stat's 10 ms ticks to
 * tell a busy core (±0.1 core per CPU), short enough for a one-solve process to notice. */
#define SERE_TEAM_FIRST_INTERVAL 0.1
#define SERE_TEAM_TAKEN			 0.3

typedef struct sere_team_state
{
	atomic_flag sampling; /* held by the thread taking a sample */
	atomic_int enabled;	  /* −1 not yet known, 0 off, 1 on */
	atomic_int cores;	  /* cores left to us at the last sample; 0: no cap (none taken, or not yet known) */
	double next;		  /* the fields below belong to the thread holding `sampling` */
	double wall, own, busy;
	int have;
} sere_team_state;

static sere_team_state sere_team_global = { ATOMIC_FLAG_INIT, -1, 0, 0.0, 0.0, 0.0, 0.0, 0 };

/* Busy seconds of the CPUs in this thread's affinity mask, and how many of them there are;
 * 0 when /proc/stat cannot be read or does not list them all. */
static inline int sere_team_cpu_busy( double* busy )
{
	cpu_set_t mask;
	CPU_ZERO( &mask );
	if ( sched_getaffinity( 0, sizeof( mask ), &mask ) != 0 )
	{
		return 0;
	}
	int fd = open( "/proc/stat", O_RDONLY | O_CLOEXEC );
	if ( fd < 0 )
	{
		return 0;
	}
	char text[16384];
	ssize_t length = 0, got;
	while ( length < (ssize_t) sizeof( text ) - 1 &&
			( got = read( fd, text + length, sizeof( text ) - 1 - (size_t) length ) ) > 0 )
	{
		length += got;
	}
	close( fd );
	text[length > 0 ? length : 0] = '\0';
	const int niced = getpriority( PRIO_PROCESS, 0 ) > 0;
	const long ticks = sysconf( _SC_CLK_TCK );
	unsigned long long sum = 0;
	int found = 0;
	/* "cpu" (all CPUs), then "cpuN user nice system idle iowait irq softirq steal ..." */
	for ( char* line = text; strncmp( line, "cpu", 3 ) == 0; )
	{
		if ( line[3] >= '0' && line[3] <= '9' )
		{
			char* at;
			long cpu = strtol( line + 3, &at, 10 );
			unsigned long long field[8] = { 0 };
			for ( int k = 0; k < 8; ++k )
			{
				field[k] = strtoull( at, &at, 10 );
			}
			if ( cpu >= 0 && cpu < CPU_SETSIZE && CPU_ISSET( (int) cpu, &mask ) )
			{
				sum += field[0] + ( niced ? field[1] : 0 ) + field[2] + field[5] + field[6] + field[7];
				found += 1;
			}
		}
		char* end = strchr( line, '\n' );
		if ( end == NULL )
		{
			break;
		}
		line = end + 1;
	}
	if ( found != CPU_COUNT( &mask ) || ticks <= 0 )
	{
		return 0;
	}
	*busy = (double) sum / (double) ticks;
	return found;
}

static inline void sere_team_sample( sere_team_state* s, double now )
{
	double busy = 0.0;
	int cpus = sere_team_cpu_busy( &busy );
	struct timespec cpu_time;
	if ( cpus == 0 || clock_gettime( CLOCK_PROCESS_CPUTIME_ID, &cpu_time ) != 0 )
	{
		atomic_store_explicit( &s->enabled, 0, memory_order_relaxed );
		return;
	}
	double own = (double) cpu_time.tv_sec + 1e-9 * (double) cpu_time.tv_nsec;
	if ( s->have && now > s->wall )
	{
		double others = ( ( busy - s->busy ) - ( own - s->own ) ) / ( now - s->wall );
		int taken = others >= SERE_TEAM_TAKEN ? (int) ( others + 1.0 - SERE_TEAM_TAKEN ) : 0;
		/* No cap while no core is taken: a caller that asks for more threads than CPUs (a
		 * test of 3 threads on 2 cores) gets them. */
		int cores = taken == 0 ? 0 : cpus - taken < 1 ? 1 : cpus - taken;
		atomic_store_explicit( &s->cores, cores, memory_order_relaxed );
	}
	s->have = 1, s->wall = now, s->own = own, s->busy = busy;
}

/* The thread count for a parallel region that the caller would run with `wanted` threads (at
 * most SERE_MAX_THREADS, base.h). */
static inline int sere_team( int wanted )
{
	wanted = wanted > SERE_MAX_THREADS ? SERE_MAX_THREADS : wanted;
	sere_team_state* s = &sere_team_global;
	if ( omp_in_parallel() )
	{
		return wanted;
	}
	int enabled = atomic_load_explicit( &s->enabled, memory_order_relaxed );
	if ( enabled < 0 )
	{
		const char* setting = getenv( "SERE_ADAPTIVE_THREADS" );
		enabled = !( setting != NULL && strcmp( setting, "0" ) == 0 );
		atomic_store_explicit( &s->enabled, enabled, memory_order_relaxed );
	}
	if ( !enabled )
	{
		return wanted;
	}
	double now = omp_get_wtime();
	if ( !atomic_flag_test_and_set_explicit( &s->sampling, memory_order_acquire ) )
	{
		/* Samples are taken whatever `wanted` is, so that the measure is fresh when a caller
		 * asks for more threads. The first window is shorter, for a process's first calls. */
		if ( now >= s->next )
		{
			s->next = now + ( s->have ? SERE_TEAM_INTERVAL : SERE_TEAM_FIRST_INTERVAL );
			sere_team_sample( s, now );
		}
		atomic_flag_clear_explicit( &s->sampling, memory_order_release );
	}
	int cores = atomic_load_explicit( &s->cores, memory_order_relaxed );
	return wanted > 1 && cores > 0 && cores < wanted ? cores : wanted;
}

/* The team of a parallel region in a kernel called with `threads` (its object's count or its
 * `threads` argument, base.h): 0 asks for the caller's OpenMP count (omp_get_max_threads()). */
static inline int sere_team_for( int32_t threads )
{
	return sere_team( threads > 0 ? threads : omp_get_max_threads() );
}

/* A choice between a kernel object's team and one thread, by the wall time a unit of its work
 * (a descent's sweep, a leaf's osmosis and shrinkage of a frame) took with each. /proc/stat does
 * not see every lost core: in spells of seconds to minutes on the 2-core virtual machine sere is
 * measured on, every CPU but ours idle, the descent's two threads each swept at half the speed
 * one thread sweeps alone (their virtual CPUs sharing one core, as far as can be told from
 * inside: no thread waited long at a barrier and neither lost its CPU in the guest), and a
 * 2-thread Table 1 frame of the plane tree ran 1.7 times as long as a 1-thread one.
 *
 * A team can also be slower than one thread from the start and stay so (a problem too small for
 * its barriers, a core shared for good, a spell that began before the first call), which its own
 * fastest run would never show.
 *
 * So the calls go in runs of SERE_TUNER_RUN, each run's seconds a unit measured. After the first
 * run, and every SERE_TUNER_RECHECK runs, one thread is tried for SERE_TUNER_TRIAL calls and
 * taken if it was SERE_TUNER_GAIN times as fast; sooner, at most every SERE_TUNER_TRY runs,
 * while the team runs past SERE_TUNER_SLOW of its fastest run (that mark rising 1% a run, so
 * that a workload that grows heavier does not look slow for ever). One thread, taken, tries the
 * team again after SERE_TUNER_TRY runs, then after twice as many each time it stays (at most
 * SERE_TUNER_RECHECK / 4: a trial of the slower team costs its share of the calls), and gives
 * way unless it is still SERE_TUNER_GAIN times as fast. Single calls' times vary too much (a
 * step's first sweep meets cold caches) for a choice on one. Results do not depend on the
 * choice (the kernels' determinism contract); SERE_ADAPTIVE_THREADS=0 turns it off with the
 * rest of this file. */
#define SERE_TUNER_RUN	   8
#define SERE_TUNER_TRIAL   4
#define SERE_TUNER_TRY	   4
#define SERE_TUNER_RECHECK 64
#define SERE_TUNER_SLOW	   1.5
#define SERE_TUNER_GAIN	   1.2

typedef struct sere_team_tuner
{
	double seconds, units; /* the current run's time and work */
	double per_unit[2];	   /* the last run's seconds a unit: [0] one thread, [1] the team; 0 unknown */
	double fastest;		   /* the team's mark: its fastest run, rising 1% a run */
	int32_t team;		   /* the team all this belongs to */
	int32_t choice;		   /* what runs: 0 one thread, 1 the team */
	int32_t calls;		   /* in the current run */
	int32_t trial;		   /* 1 while the current run tries the other choice */
	int32_t since;		   /* runs since the last trial */
	int32_t wait;		   /* runs one thread waits before it tries the team */
} sere_team_tuner;

/* The team for a call that sere_team_for would give `team` threads. */
static inline int sere_tuner_team( sere_team_tuner* u, int team )
{
	if ( team <= 1 || atomic_load_explicit( &sere_team_global.enabled, memory_order_relaxed ) == 0 )
	{
		return team;
	}
	if ( team != u->team )
	{
		*u = ( sere_team_tuner ){ 0.0, 0.0, { 0.0, 0.0 }, 0.0, team, 1, 0, 0, SERE_TUNER_RECHECK, SERE_TUNER_TRY };
	}
	return u->choice ? team : 1;
}

/* Records that a call given `used` threads took `seconds` for `units` units of work. */
static inline void sere_tuner_record( sere_team_tuner* u, int used, double seconds, double units )
{
	if ( u->team <= 1 || used != ( u->choice ? u->team : 1 ) )
	{
		return;
	}
	u->seconds += seconds, u->units += units, u->calls += 1;
	if ( u->calls < ( u->trial ? SERE_TUNER_TRIAL : SERE_TUNER_RUN ) )
	{
		return;
	}
	const double per_unit = u->units > 0.0 ? u->seconds / u->units : 0.0;
	u->seconds = u->units = 0.0, u->calls = 0;
	if ( !( per_unit > 0.0 ) )
	{
		return;
	}
	u->per_unit[u->choice] = per_unit;
	if ( u->choice )
	{
		u->fastest = u->fastest == 0.0 || per_unit < 1.01 * u->fastest ? per_unit : 1.01 * u->fastest;
	}
	if ( u->trial )
	{
		const int stayed = u->choice; /* one thread tried the team, and stays */
		u->trial = 0, u->since = 0;
		u->choice = !( u->per_unit[0] > 0.0 && SERE_TUNER_GAIN * u->per_unit[0] < u->per_unit[1] );
		u->wait = u->choice ? SERE_TUNER_TRY
				  : stayed	? ( 2 * u->wait < SERE_TUNER_RECHECK / 4 ? 2 * u->wait : SERE_TUNER_RECHECK / 4 )
							: u->wait;
		return;
	}
	u->since += 1;
	if ( u->since >= SERE_TUNER_RECHECK || ( !u->choice && u->since >= u->wait ) ||
		 ( u->choice && u->since >= SERE_TUNER_TRY && per_unit > SERE_TUNER_SLOW * u->fastest ) )
	{
		u->trial = 1, u->choice = !u->choice;
	}
}

/* Thread `tid` of `team`'s contiguous share [*first, *last) of [begin, end), cut as OpenMP's
 * static schedule cuts it: for work a kernel splits by hand, where its threads then meet at a
 * sere_spin_barrier instead of an `omp for`'s own barrier. */
static inline void sere_team_share( int32_t begin, int32_t end, int tid, int team, int32_t* first, int32_t* last )
{
	const int64_t n = (int64_t) end - begin;
	*first = begin + (int32_t) ( n * tid / team );
	*last = begin + (int32_t) ( n * ( tid + 1 ) / team );
}

/* Slot `slot` of per-block sums kept four doubles a block (partial[4 b + slot]), added in block
 * order: each block's sum is one thread's, so the total has the same bits for any thread count. */
static inline double sere_block_sum( const double* partial, int32_t blocks, int slot )
{
	double sum = 0.0;
	for ( int32_t b = 0; b < blocks; ++b )
	{
		sum += partial[4 * (size_t) b + (size_t) slot];
	}
	return sum;
}

/* A sense-free spin barrier for the threads of one parallel region. libgomp's barrier (the one
 * ending every `omp for`) makes a futex system call at each release, even for a team of one
 * (0.4 µs a barrier at one thread on this machine's virtual CPUs, all of it the call); a PBD
 * sweep or a CG iteration crosses several, so those kernels synchronize with this one instead
 * (0.2–0.5 µs for two threads, nothing for one). Zeroed memory is a ready barrier. */
typedef struct sere_spin_barrier
{
	_Alignas( 64 ) atomic_uint arrived;
	_Alignas( 64 ) atomic_uint generation;
} sere_spin_barrier;

/* A waiting thread spins this long, then naps SERE_NAP_NANOSECONDS at a time. */
#define SERE_SPIN_SECONDS	 100e-6
#define SERE_NAP_NANOSECONDS 50000

typedef struct sere_wait
{
	double start;
	unsigned spins;
} sere_wait;

#define SERE_WAIT_START ( ( sere_wait ){ -1.0, 0 } )

/* One turn of a wait loop. Spin while the wait is short (a sweep or an iteration is tens of µs);
 * past SERE_SPIN_SECONDS another thread has most likely lost its core to some other process, so
 * nap instead: an idle core lets the scheduler move that thread over, where spinning (or
 * yielding) would keep it queued behind the other process for a whole time slice
 * (milliseconds). */
static inline void sere_wait_step( sere_wait* wait )
{
	if ( ++wait->spins % 1024 == 0 )
	{
		double now = omp_get_wtime();
		wait->start = wait->start < 0.0 ? now : wait->start;
		if ( now - wait->start > SERE_SPIN_SECONDS )
		{
			const struct timespec nap = { 0, SERE_NAP_NANOSECONDS };
			nanosleep( &nap, NULL );
		}
	}
}

/* Waits until all `threads` threads of the region have arrived; what each wrote before is then
 * visible to all. */
static inline void sere_spin_barrier_wait( sere_spin_barrier* barrier, int threads )
{
	if ( threads == 1 )
	{
		return;
	}
	unsigned generation = atomic_load_explicit( &barrier->generation, memory_order_relaxed );
	if ( atomic_fetch_add_explicit( &barrier->arrived, 1u, memory_order_acq_rel ) == (unsigned) threads - 1 )
	{
		atomic_store_explicit( &barrier->arrived, 0u, memory_order_relaxed );
		atomic_store_explicit( &barrier->generation, generation + 1u, memory_order_release );
		return;
	}
	sere_wait wait = SERE_WAIT_START;
	while ( atomic_load_explicit( &barrier->generation, memory_order_acquire ) == generation )
	{
		sere_wait_step( &wait );
	}
}
