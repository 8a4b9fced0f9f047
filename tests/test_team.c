/* The thread team's tuner (core/internal/team.h: sere_team_tuner), which chooses between a kernel
 * object's team and one thread by the seconds a unit of work took with each. The calls here are
 * simulated: each is told how long it took with the threads the tuner gave it, so the tests are
 * exact, not timed. Each test sets the team state's switch itself, since the suite runs with
 * SERE_ADAPTIVE_THREADS=0.
 * _GNU_SOURCE: internal/team.h (sched_getaffinity). */
#define _GNU_SOURCE

#include "core/internal/team.h"

#include <criterion/criterion.h>

/* Seconds a unit of work, by the threads a call runs with. */
typedef struct machine
{
	double one, team;
} machine;

/* Runs `calls` calls of 10 units each on `m` and returns how many ran with one thread. */
static int run_calls( sere_team_tuner* u, machine m, int calls )
{
	int single = 0;
	for ( int k = 0; k < calls; ++k )
	{
		const int used = sere_tuner_team( u, 2 );
		cr_assert( used == 1 || used == 2, "the tuner gave %d threads of 2", used );
		single += used == 1;
		sere_tuner_record( u, used, 10.0 * ( used == 1 ? m.one : m.team ), 10.0 );
	}
	return single;
}

/* The most calls one thread runs in `calls` on a machine where the team is the faster: its
 * trials, after the first run and every SERE_TUNER_RECHECK runs. */
static int rechecks( int calls )
{
	return SERE_TUNER_TRIAL * ( 1 + calls / ( SERE_TUNER_RECHECK * SERE_TUNER_RUN ) );
}

/* The quiet machine: two threads take 0.7 of one's time (the descent's sweep here). */
static const machine quiet = { 1.0, 0.7 };
/* A spell of another guest's: the two threads each at half speed, slower than one (the 2-thread
 * Table 1 frames ran at about twice the 1-thread time in such spells). */
static const machine spell = { 1.0, 2.0 };

Test( team, tuner_keeps_the_team_on_a_quiet_machine )
{
	atomic_store( &sere_team_global.enabled, 1 ); /* on */
	sere_team_tuner u = { 0 };
	const int single = run_calls( &u, quiet, 2000 );
	cr_expect_geq( single, SERE_TUNER_TRIAL, "one thread was never tried" );
	cr_expect_leq( single, rechecks( 2000 ), "one thread ran %d calls on a quiet machine, more than its trials",
				   single );
	/* a team a little slower than its fastest run (within SERE_TUNER_SLOW) is not doubted sooner */
	const machine slower = { 1.0, 0.7 * 1.4 };
	const int doubted = run_calls( &u, slower, 2000 );
	cr_expect_leq( doubted, rechecks( 2000 ), "a team within 1.5x of its fastest was doubted: %d calls on one thread",
				   doubted );
	cr_expect_eq( u.choice, 1, "the team is not the choice" );
}

Test( team, tuner_takes_one_thread_for_a_small_problem )
{
	atomic_store( &sere_team_global.enabled, 1 ); /* on */
	sere_team_tuner u = { 0 };
	/* a team slower than one thread from its first call on (team.h): never slow against its own
	 * fastest run, so only the trials can find one thread */
	const machine small = { 1.5, 3.6 };
	const int calls = 2000, team = calls - run_calls( &u, small, calls );
	const int trials = calls / ( SERE_TUNER_TRY * SERE_TUNER_RUN ) + 1;
	cr_expect_leq( team, SERE_TUNER_RUN + trials * SERE_TUNER_TRIAL,
				   "the team ran %d of %d calls where one thread is 2.4x as fast", team, calls );
}

Test( team, tuner_takes_one_thread_in_a_spell_and_gives_it_back )
{
	atomic_store( &sere_team_global.enabled, 1 ); /* on */
	sere_team_tuner u = { 0 };
	run_calls( &u, quiet, 200 );
	/* the spell: after at most SERE_TUNER_TRY runs and a trial, one thread; then the team only on
	 * its trials, SERE_TUNER_TRIAL calls in every SERE_TUNER_TRY runs */
	const int lag = SERE_TUNER_TRY * SERE_TUNER_RUN + SERE_TUNER_TRIAL;
	const int first = run_calls( &u, spell, lag );
	cr_expect_geq( first, SERE_TUNER_TRIAL, "a spell of %d calls took one thread in only %d", lag, first );
	const int long_spell = 20 * lag, single = run_calls( &u, spell, long_spell );
	const int team = long_spell - single;
	/* one thread tries the team after 4, 8, then 16 runs (SERE_TUNER_RECHECK / 4) at most */
	const int trials = long_spell / ( SERE_TUNER_RECHECK / 4 * SERE_TUNER_RUN ) + 3;
	cr_expect_leq( team, trials * SERE_TUNER_TRIAL, "in the spell the team ran %d of %d calls: more than %d trials'",
				   team, long_spell, trials );
	cr_expect_gt( team, 0, "one thread never tried the team again" );
	/* the spell ends: the next trial of the team gives it back, and it stays */
	run_calls( &u, quiet, lag );
	const int after = run_calls( &u, quiet, 2000 );
	cr_expect_leq( after, rechecks( 2000 ), "one thread kept after the spell ended: %d calls of 2000", after );
}

Test( team, tuner_keeps_the_team_when_one_thread_is_not_clearly_faster )
{
	atomic_store( &sere_team_global.enabled, 1 ); /* on */
	sere_team_tuner u = { 0 };
	run_calls( &u, quiet, 200 );
	/* slower than 1.5x its fastest, so one thread is tried, but one thread is not 1.2x as fast:
	 * only the trials run with it */
	const machine close = { 1.0, 1.1 };
	const int calls = 2000, single = run_calls( &u, close, calls );
	const int trials = calls / ( SERE_TUNER_TRY * SERE_TUNER_RUN + SERE_TUNER_TRIAL ) + 1;
	cr_expect_gt( single, 0, "a slowed team never tried one thread" );
	cr_expect_leq( single, trials * SERE_TUNER_TRIAL, "one thread ran %d calls, more than %d trials' worth", single,
				   trials );
}

Test( team, tuner_is_off_with_adaptive_threads_off )
{
	atomic_store( &sere_team_global.enabled, 0 ); /* off */
	sere_team_tuner u = { 0 };
	run_calls( &u, quiet, 200 );
	cr_expect_eq( run_calls( &u, spell, 2000 ), 0, "SERE_ADAPTIVE_THREADS=0 and the tuner chose one thread" );
}

Test( team, tuner_starts_over_when_the_team_changes )
{
	atomic_store( &sere_team_global.enabled, 1 ); /* on */
	sere_team_tuner u = { 0 };
	run_calls( &u, quiet, 200 );
	cr_assert_gt( run_calls( &u, spell, 1000 ), 0 );
	/* a team of 3: what was measured for 2 says nothing of it */
	cr_expect_eq( sere_tuner_team( &u, 3 ), 3, "a new team started on one thread" );
	cr_expect_eq( u.per_unit[0], 0.0, "one thread's measure outlived the team it was compared with" );
	cr_expect_eq( sere_tuner_team( &u, 1 ), 1, "one thread asked for, another count given" );
}
