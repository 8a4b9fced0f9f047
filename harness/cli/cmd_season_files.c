/* sere season — the chain file (data/seasons/maple.chain describes the format) and the
 * temperature/humidity schedule (Tang Sec. 5: the Markov chain of leaf states and the weather
 * that weighs its transitions). */
#define _POSIX_C_SOURCE 200809L
#include "cli/cmd_season_shared.h"

#include "common/io.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int fail_line( const char* path, int line, const char* format, ... ) __attribute__( ( format( printf, 3, 4 ) ) );

static int fail_line( const char* path, int line, const char* format, ... )
{
	char what[4096 + 600];
	va_list args;
	va_start( args, format );
	sere_fail_at( SERE_ERR_PARSE, what, sizeof( what ), path, line, format, args );
	va_end( args );
	fprintf( stderr, "sere season: %s\n", what );
	return -1;
}

static int find_state( const chain_file* c, const char* name )
{
	for ( int32_t s = 0; s < c->state_count; ++s )
	{
		if ( strcmp( c->name[s], name ) == 0 )
		{
			return s;
		}
	}
	return -1;
}

/* Splits a line into at most max words (comments after '#' dropped); returns the count. */
static int split_words( char* line, char** words, int max )
{
	char* hash = strchr( line, '#' );
	if ( hash != NULL )
	{
		*hash = '\0';
	}
	int n = 0;
	for ( char *save = NULL, *w = strtok_r( line, " \t\r\n", &save ); w != NULL;
		  w = strtok_r( NULL, " \t\r\n", &save ) )
	{
		if ( n == max )
		{
			return max + 1;
		}
		words[n++] = w;
	}
	return n;
}

static int number( const char* text, double* value )
{
	char* end;
	errno = 0;
	*value = strtod( text, &end );
	return *text != '\0' && *end == '\0' && errno == 0 && isfinite( *value );
}

/* The next line of f, of any length, into *text (getline's buffer); 1, or 0 at the end, or -1
 * after printing "PATH:LINE: ..." for a NUL byte or "PATH: cannot read: ..." for an error. */
static int next_line( FILE* f, const char* path, int line, char** text, size_t* capacity )
{
	errno = 0;
	ssize_t got = getline( text, capacity, f );
	if ( got < 0 )
	{
		return ferror( f ) ? fail_line( path, 0, "cannot read: %s", strerror( errno != 0 ? errno : EIO ) ) : 0;
	}
	if ( memchr( *text, '\0', (size_t) got ) != NULL )
	{
		return fail_line( path, line, "a NUL byte (this is not a text file)" );
	}
	return 1;
}

static int probability_list( char** words, double* out, const char* path, int line, const char* what )
{
	for ( int k = 0; k < 4; ++k )
	{
		if ( !number( words[k], &out[k] ) || out[k] < 0.0 || out[k] > 1.0 )
		{
			return fail_line( path, line, "%s: '%s' is not a probability in [0, 1]", what, words[k] );
		}
	}
	return 0;
}

typedef int line_fn( void* user, char** words, int count, const char* path, int line );

/* Every line of a text file with words (comments after '#' dropped, at most max_words: one
 * more counts as too many for the handler to refuse), handed to each_line until it fails.
 * 0, or -1 after printing why. */
static int read_lines( const char* path, int max_words, line_fn* each_line, void* user )
{
	FILE* f = fopen( path, "r" );
	if ( f == NULL )
	{
		return fail_line( path, 0, "cannot open: %s", strerror( errno ) );
	}
	char* text = NULL;
	size_t capacity = 0;
	int line = 0, bad = 0, more;
	while ( !bad && ( more = next_line( f, path, line + 1, &text, &capacity ) ) != 0 )
	{
		line += 1;
		if ( more < 0 )
		{
			bad = -1;
			break;
		}
		char* w[16];
		int n = split_words( text, w, max_words );
		if ( n > 0 )
		{
			bad = each_line( user, w, n, path, line );
		}
	}
	free( text );
	fclose( f );
	return bad ? -1 : 0;
}

/* corners COLD WARM DRY WET: the temperature and humidity of the chain's four corners. */
static int chain_corners( chain_file* c, char** w, int n, const char* path, int line )
{
	int bad = 0;
	double v[4];
	if ( n != 5 || !number( w[1], &v[0] ) || !number( w[2], &v[1] ) || !number( w[3], &v[2] ) ||
		 !number( w[4], &v[3] ) )
	{
		bad = fail_line( path, line, "expected 'corners COLD WARM DRY WET' (four numbers)" );
	}
	else if ( !( v[0] < v[1] ) || !( v[2] < v[3] ) )
	{
		bad = fail_line( path, line, "corners need COLD < WARM and DRY < WET" );
	}
	else
	{
		c->chain.cold = v[0], c->chain.warm = v[1], c->chain.dry = v[2], c->chain.wet = v[3];
		c->have_corners = 1;
	}
	return bad;
}

/* state NAME R G B LEVEL [fallen] STAY_WC STAY_WW STAY_DC STAY_DW. */
static int chain_state( chain_file* c, char** w, int n, const char* path, int line )
{
	int bad = 0;
	int fallen = n == 11 && strcmp( w[6], "fallen" ) == 0;
	double rgb[3], level;
	if ( n != 10 && !fallen )
	{
		bad = fail_line( path, line, "expected 'state NAME R G B LEVEL [fallen] STAY_WC STAY_WW STAY_DC STAY_DW'" );
	}
	else if ( c->state_count == MAX_STATES )
	{
		bad = fail_line( path, line, "more than %d states", MAX_STATES );
	}
	else if ( strlen( w[1] ) >= NAME_SIZE || find_state( c, w[1] ) >= 0 )
	{
		bad = fail_line( path, line, "state name '%s' is %s", w[1],
						 strlen( w[1] ) >= NAME_SIZE ? "too long" : "used twice" );
	}
	else if ( !number( w[2], &rgb[0] ) || !number( w[3], &rgb[1] ) || !number( w[4], &rgb[2] ) || rgb[0] < 0 ||
			  rgb[0] > 255 || rgb[1] < 0 || rgb[1] > 255 || rgb[2] < 0 || rgb[2] > 255 )
	{
		bad = fail_line( path, line, "state '%s': the color needs three values in 0..255", w[1] );
	}
	else if ( !number( w[5], &level ) || level < 0 || level > 63 || level != floor( level ) )
	{
		bad = fail_line( path, line, "state '%s': LEVEL '%s' is not a whole number in 0..63", w[1], w[5] );
	}
	else if ( probability_list( w + ( fallen ? 7 : 6 ), c->stay + 4 * c->state_count, path, line, w[1] ) == 0 )
	{
		int32_t s = c->state_count++;
		snprintf( c->name[s], NAME_SIZE, "%s", w[1] );
		for ( int k = 0; k < 3; ++k )
		{
			c->rgb[s][k] = (uint8_t) lround( rgb[k] );
		}
		c->level[s] = (int32_t) level;
		c->fallen[s] = fallen;
	}
	else
	{
		bad = -1;
	}
	return bad;
}

/* transition FROM TO G_WC G_WW G_DC G_DW, between declared states. */
static int chain_transition( chain_file* c, char** w, int n, const char* path, int line )
{
	int bad = 0;
	int from = n == 7 ? find_state( c, w[1] ) : -1, to = n == 7 ? find_state( c, w[2] ) : -1;
	if ( n != 7 )
	{
		bad = fail_line( path, line, "expected 'transition FROM TO G_WC G_WW G_DC G_DW'" );
	}
	else if ( from < 0 || to < 0 )
	{
		bad = fail_line( path, line, "unknown state '%s' (states are declared before their transitions)",
						 from < 0 ? w[1] : w[2] );
	}
	else if ( c->transition_count == MAX_TRANSITION )
	{
		bad = fail_line( path, line, "more than %d transitions", MAX_TRANSITION );
	}
	else
	{
		sere_markov_transition* t = &c->transitions[c->transition_count];
		t->from = from, t->to = to;
		bad = probability_list( w + 3, t->weight, path, line, "transition" );
		c->transition_count += bad == 0;
	}
	return bad;
}

/* One line of a chain file split into words; 0, or -1 after printing why. */
static int chain_line( void* user, char** w, int n, const char* path, int line )
{
	chain_file* c = user;
	if ( strcmp( w[0], "corners" ) == 0 )
	{
		return chain_corners( c, w, n, path, line );
	}
	if ( strcmp( w[0], "state" ) == 0 )
	{
		return chain_state( c, w, n, path, line );
	}
	if ( strcmp( w[0], "transition" ) == 0 )
	{
		return chain_transition( c, w, n, path, line );
	}
	if ( strcmp( w[0], "initial" ) == 0 )
	{
		c->initial = n == 2 ? find_state( c, w[1] ) : -1;
		return c->initial < 0 ? fail_line( path, line, "expected 'initial NAME' with a declared state" ) : 0;
	}
	return fail_line( path, line, "unknown keyword '%s' (corners, state, transition, initial)", w[0] );
}

int season_read_chain( const char* path, chain_file* c )
{
	memset( c, 0, sizeof( *c ) );
	c->initial = -1;
	if ( read_lines( path, 15, chain_line, c ) != 0 )
	{
		return -1;
	}
	if ( c->state_count == 0 || !c->have_corners || c->initial < 0 )
	{
		return fail_line( path, 0, "missing %s",
						  c->state_count == 0 ? "states"
						  : !c->have_corners  ? "'corners'"
											  : "'initial'" );
	}
	c->chain.state_count = c->state_count;
	c->chain.stay = c->stay;
	c->chain.transition_count = c->transition_count;
	c->chain.transitions = c->transitions;
	sere_status status = sere_markov_validate( &c->chain );
	if ( status != SERE_OK )
	{
		return fail_line( path, 0,
						  "not a usable chain (%s): a transition from a state to itself, one given twice, or more than "
						  "%d successors of a state",
						  sere_status_text( status ), SERE_MARKOV_MAX_OUTCOMES - 1 );
	}
	return 0;
}

/* DAY TEMPERATURE HUMIDITY [LABEL]. */
static int schedule_line( void* user, char** w, int n, const char* path, int line )
{
	schedule* s = user;
	int bad = 0;
	double day, t, h;
	if ( n < 3 || n > 4 || !number( w[0], &day ) || !number( w[1], &t ) || !number( w[2], &h ) )
	{
		bad = fail_line( path, line, "expected 'DAY TEMPERATURE HUMIDITY [LABEL]'" );
	}
	else if ( day != floor( day ) || day < 0 || day > MAX_DAYS || ( s->count > 0 && day <= s->day[s->count - 1] ) ||
			  ( s->count == 0 && day != 0 ) )
	{
		bad = fail_line( path, line, "day %s: days are whole numbers from 0 (the first line) to %d, increasing", w[0],
						 MAX_DAYS );
	}
	else if ( t < -90.0 || t > 70.0 )
	{
		bad = fail_line( path, line, "temperature %s deg C is outside [-90, 70]", w[1] );
	}
	else if ( h < 0.0 || h > 1.0 )
	{
		bad = fail_line( path, line, "humidity %s is outside [0, 1] (relative humidity as a fraction)", w[2] );
	}
	else if ( s->count == MAX_SCHEDULE )
	{
		bad = fail_line( path, line, "more than %d lines", MAX_SCHEDULE );
	}
	else if ( n == 4 && strlen( w[3] ) >= NAME_SIZE )
	{
		bad = fail_line( path, line, "label '%s' is longer than %d characters", w[3], NAME_SIZE - 1 );
	}
	else
	{
		s->day[s->count] = (int32_t) day;
		s->temperature[s->count] = t;
		s->humidity[s->count] = h;
		snprintf( s->label[s->count], NAME_SIZE, "%s", n == 4 ? w[3] : "" );
		s->count += 1;
	}
	return bad;
}

int season_read_schedule( const char* path, schedule* s )
{
	memset( s, 0, sizeof( *s ) );
	int bad = read_lines( path, 5, schedule_line, s );
	if ( !bad && s->count < 2 )
	{
		bad = fail_line( path, 0, "a schedule needs at least two days" );
	}
	return bad ? -1 : 0;
}

void season_weather( const schedule* s, int32_t day, double* t, double* h )
{
	int32_t k = 0;
	while ( k + 1 < s->count && s->day[k + 1] <= day )
	{
		k += 1;
	}
	if ( k + 1 == s->count )
	{
		*t = s->temperature[k], *h = s->humidity[k];
		return;
	}
	double a = (double) ( day - s->day[k] ) / (double) ( s->day[k + 1] - s->day[k] );
	*t = s->temperature[k] + a * ( s->temperature[k + 1] - s->temperature[k] );
	*h = s->humidity[k] + a * ( s->humidity[k + 1] - s->humidity[k] );
}
