/* The one command-line parser (harness/cli/options.c): every kind of option stores what it should,
 * bad values are refused with the message users see, lists keep their order, --help stops. */
#include "cli/options.h"

#include <criterion/criterion.h>
#include <criterion/redirect.h>
#include <math.h>
#include <string.h>

typedef struct values
{
	int flag;
	long long count;
	double real;
	const char *text, *dir;
	sere_option_list list;
	int choice;
} values;

static const char* const kChoices[] = { "paper", "conservative", NULL };

static sere_status parse( values* v, sere_options_result* r, int argc, char** argv )
{
	*v = ( values ){ .count = -1, .real = NAN, .choice = -1 };
	const sere_option table[] = {
		{ "--flag", SERE_OPTION_FLAG, &v->flag, 0, 0, NULL },
		{ "--count", SERE_OPTION_COUNT, &v->count, 1, 100, NULL },
		{ "--real", SERE_OPTION_REAL, &v->real, 0.0, 1.0, NULL },
		{ "--text", SERE_OPTION_TEXT, &v->text, 0, 0, NULL },
		{ "--out", SERE_OPTION_DIR, &v->dir, 0, 0, NULL },
		{ "--set", SERE_OPTION_LIST, &v->list, 0, 0, NULL },
		{ "--mode", SERE_OPTION_CHOICE, &v->choice, 0, 0, kChoices },
	};
	return sere_options_parse( "demo", argc, argv, table, sizeof( table ) / sizeof( table[0] ), 1, "LEAF", r );
}

Test( options, every_kind_stores_its_value )
{
	char* argv[] = { "demo", "--flag", "--count", "42",	   "--real", "0.25",   "--text",	   "-x",	   "--out",
					 "o",	 "--set",  "a=1",	  "--set", "b=2",	 "--mode", "conservative", "leaf.leaf" };
	values v;
	sere_options_result r;
	cr_assert_eq( parse( &v, &r, sizeof( argv ) / sizeof( argv[0] ), argv ), SERE_OK );
	cr_expect_eq( v.flag, 1 );
	cr_expect_eq( v.count, 42 );
	cr_expect_eq( v.real, 0.25 ); /* 0.25 is exact in binary: strtod gives it to the bit */
	cr_expect_str_eq( v.text, "-x", "a value may start with a dash" );
	cr_expect_str_eq( v.dir, "o" );
	cr_assert_eq( v.list.count, 2 );
	cr_expect_str_eq( v.list.items[0], "a=1", "the list keeps the command line's order" );
	cr_expect_str_eq( v.list.items[1], "b=2" );
	cr_expect_eq( v.choice, 1 );
	cr_assert_eq( r.positional_count, 1 );
	cr_expect_str_eq( r.positional[0], "leaf.leaf" );
	cr_expect_eq( r.help, 0 );
}

Test( options, help_stops_the_parse )
{
	char* argv[] = { "demo", "--count", "5", "-h", "--bogus" };
	values v;
	sere_options_result r;
	cr_assert_eq( parse( &v, &r, 5, argv ), SERE_OK, "--help wins over a later bad option" );
	cr_expect_eq( r.help, 1 );
	cr_expect_eq( v.count, 5 );
}

/* A bad command line is refused (its message is checked with the others below). */
static void refused( int argc, char** argv )
{
	values v;
	sere_options_result r;
	cr_expect_eq( parse( &v, &r, argc, argv ), SERE_ERR_ARGUMENT, "%s accepted", argv[1] );
	fflush( stderr );
}

Test( options, bad_values_are_refused_with_a_message, .init = cr_redirect_stderr )
{
	char* out_of_range[] = { "demo", "--count", "101" };
	char* not_whole[] = { "demo", "--count", "3.5" };
	char* not_finite[] = { "demo", "--real", "inf" };
	char* empty_dir[] = { "demo", "--out", "" };
	char* bad_choice[] = { "demo", "--mode", "fast" };
	char* unknown[] = { "demo", "--bogus" };
	char* no_value[] = { "demo", "--count" };
	char* two_leaves[] = { "demo", "a.leaf", "b.leaf" };
	refused( 3, out_of_range );
	refused( 3, not_whole );
	refused( 3, not_finite );
	refused( 3, empty_dir );
	refused( 3, bad_choice );
	refused( 2, unknown );
	refused( 2, no_value );
	refused( 3, two_leaves );
	cr_expect_stderr_eq_str( "sere demo: --count takes a whole number from 1 to 100, not '101'\n"
							 "sere demo: --count takes a whole number from 1 to 100, not '3.5'\n"
							 "sere demo: --real takes a number from 0 to 1, not 'inf'\n"
							 "sere demo: --out needs a directory name, not an empty string\n"
							 "sere demo: --mode takes one of 'paper', 'conservative', not 'fast'\n"
							 "sere demo: unknown option '--bogus' (see sere demo --help)\n"
							 "sere demo: --count needs a value (see sere demo --help)\n"
							 "sere demo: one LEAF only, got 'a.leaf' and 'b.leaf'\n" );
}

Test( options, a_list_holds_at_most_its_room, .init = cr_redirect_stderr )
{
	char* argv[2 * SERE_OPTION_LIST_MAX + 3];
	argv[0] = "demo";
	for ( int k = 0; k <= SERE_OPTION_LIST_MAX; ++k )
	{
		argv[1 + 2 * k] = "--set";
		argv[2 + 2 * k] = "a=1";
	}
	values v;
	sere_options_result r;
	cr_expect_eq( parse( &v, &r, 2 * SERE_OPTION_LIST_MAX + 1, argv ), SERE_OK, "a full list is accepted" );
	cr_expect_eq( v.list.count, SERE_OPTION_LIST_MAX );
	cr_expect_eq( parse( &v, &r, 2 * SERE_OPTION_LIST_MAX + 3, argv ), SERE_ERR_ARGUMENT, "one more is refused" );
}
