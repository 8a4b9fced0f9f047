/* sere — the L-system tree of lsystem.h: parallel rewriting, then one turtle walk. */
#include "season/lsystem.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define DEG 0.017453292519943295

/* The maple-like grammar of sere_lsystem_params_default: a trunk of three segments, then every
 * apex A grows three branches, each a segment with a leaf at its end and a new apex, rolled by
 * the divergence angle between them. */
static const sere_lsystem_rule default_rules[] = {
	{ 'A', "![&FLA]/[&FLA]/[&FLA]" },
};

sere_lsystem_params sere_lsystem_params_default( void )
{
	return ( sere_lsystem_params ){
		.axiom = "FFFA",
		.rules = default_rules,
		.rule_count = 1,
		.iterations = 6,
		.max_symbols = 1 << 26,
		.angle_deg = 32.0,
		.roll_deg = 137.5,
		.length = 1.0,
		.radius = 0.12,
		.length_ratio = 0.8,
		.radius_ratio = 0.62,
		.jitter_deg = 12.0,
		.leaf_droop_deg = 20.0,
		.seed = 2013,
	};
}

static sere_status rule_table( const sere_lsystem_params* params, const char* table[256] )
{
	memset( table, 0, 256 * sizeof( table[0] ) );
	if ( params == NULL || params->axiom == NULL || params->iterations < 0 || params->rule_count < 0 ||
		 ( params->rule_count > 0 && params->rules == NULL ) || params->max_symbols < 1 )
	{
		return SERE_ERR_ARGUMENT;
	}
	for ( int32_t r = 0; r < params->rule_count; ++r )
	{
		unsigned char symbol = (unsigned char) params->rules[r].symbol;
		if ( params->rules[r].replacement == NULL || symbol == 0 || table[symbol] != NULL )
		{
			return SERE_ERR_ARGUMENT;
		}
		table[symbol] = params->rules[r].replacement;
	}
	return SERE_OK;
}

sere_status sere_lsystem_rewrite( const sere_lsystem_params* params, char** out, int64_t* length )
{
	const char* table[256];
	sere_status status = rule_table( params, table );
	if ( status != SERE_OK || out == NULL || length == NULL )
	{
		return status != SERE_OK ? status : SERE_ERR_ARGUMENT;
	}
	int64_t n = (int64_t) strlen( params->axiom );
	if ( n > params->max_symbols )
	{
		return SERE_ERR_CAPACITY;
	}
	char* current = malloc( (size_t) n + 1 );
	if ( current == NULL )
	{
		return SERE_ERR_MEMORY;
	}
	memcpy( current, params->axiom, (size_t) n + 1 );
	int64_t replacement_length[256];
	for ( int c = 0; c < 256; ++c )
	{
		replacement_length[c] = table[c] != NULL ? (int64_t) strlen( table[c] ) : 1;
	}
	for ( int32_t it = 0; it < params->iterations; ++it )
	{
		int64_t next_length = 0;
		for ( int64_t i = 0; i < n; ++i )
		{
			next_length += replacement_length[(unsigned char) current[i]];
			if ( next_length > params->max_symbols )
			{
				free( current );
				return SERE_ERR_CAPACITY;
			}
		}
		char* next = malloc( (size_t) next_length + 1 );
		if ( next == NULL )
		{
			free( current );
			return SERE_ERR_MEMORY;
		}
		int64_t k = 0;
		for ( int64_t i = 0; i < n; ++i )
		{
			const char* r = table[(unsigned char) current[i]];
			if ( r != NULL )
			{
				int64_t m = replacement_length[(unsigned char) current[i]];
				memcpy( next + k, r, (size_t) m );
				k += m;
			}
			else
			{
				next[k++] = current[i];
			}
		}
		next[k] = '\0';
		free( current );
		current = next;
		n = next_length;
	}
	*out = current;
	*length = n;
	return SERE_OK;
}

typedef struct turtle
{
	double p[3];
	double h[3], l[3], u[3];
	double length, radius;
} turtle;

/* A uniform value in [−1, 1] for symbol index i (SplitMix64's finalizer over seed and index). */
static double jitter( uint64_t seed, int64_t i, int salt )
{
	uint64_t z = seed ^ ( (uint64_t) i * 0x9E3779B97F4A7C15ull ) ^ ( (uint64_t) salt << 56 );
	z = ( z ^ ( z >> 30 ) ) * 0xBF58476D1CE4E5B9ull;
	z = ( z ^ ( z >> 27 ) ) * 0x94D049BB133111EBull;
	z ^= z >> 31;
	return (double) ( z >> 11 ) * ( 2.0 / 9007199254740992.0 ) - 1.0;
}

/* Rotates the pair (a, b) of frame vectors by angle in their plane: a' = a cos + b sin,
 * b' = −a sin + b cos (ABOP's R_U, R_L and R_H are all of this form). */
static void rotate_pair( double* a, double* b, double angle )
{
	double c = cos( angle ), s = sin( angle );
	for ( int k = 0; k < 3; ++k )
	{
		double ak = a[k], bk = b[k];
		a[k] = ak * c + bk * s;
		b[k] = -ak * s + bk * c;
	}
}

static void normalize( double* v )
{
	double n = sqrt( v[0] * v[0] + v[1] * v[1] + v[2] * v[2] );
	v[0] /= n, v[1] /= n, v[2] /= n;
}

void sere_tree_destroy( sere_tree* tree )
{
	if ( tree == NULL )
	{
		return;
	}
	free( tree->x0 );
	free( tree->leaf_x );
	memset( tree, 0, sizeof( *tree ) );
}

/* F and f: the turtle moves one step along its heading; F also draws the branch segment ns
 * (the radius tapering by the radius ratio along it). Returns the segments drawn, 0 or 1. */
static int move_forward( turtle* t, int draw, const sere_lsystem_params* params, sere_tree* tree, int32_t ns )
{
	double end[3];
	for ( int k = 0; k < 3; ++k )
	{
		end[k] = t->p[k] + t->length * t->h[k];
	}
	if ( draw )
	{
		tree->x0[ns] = (float) t->p[0], tree->y0[ns] = (float) t->p[1], tree->z0[ns] = (float) t->p[2];
		tree->x1[ns] = (float) end[0], tree->y1[ns] = (float) end[1], tree->z1[ns] = (float) end[2];
		tree->r0[ns] = (float) t->radius;
		tree->r1[ns] = (float) ( t->radius * params->radius_ratio );
	}
	memcpy( t->p, end, sizeof( end ) );
	return draw;
}

/* L: leaf nl at the turtle, its blade along the heading flattened onto the ground plane (the
 * left vector when the heading is vertical), turned at random, then tilted down by the droop. */
static void add_leaf( const turtle* t, uint64_t seed, int64_t i, double droop, sere_tree* tree, int32_t nl )
{
	double d[3] = { t->h[0], t->h[1], 0.0 };
	if ( d[0] * d[0] + d[1] * d[1] < 1e-6 )
	{
		d[0] = t->l[0], d[1] = t->l[1];
	}
	normalize( d );
	double yaw = 0.7 * jitter( seed, i, 1 ), c = cos( yaw ), sn = sin( yaw );
	double dx = c * d[0] - sn * d[1], dy = sn * d[0] + c * d[1];
	double dir[3] = { cos( droop ) * dx, cos( droop ) * dy, -sin( droop ) };
	/* the face normal: +z made orthogonal to the blade direction */
	double nrm[3] = { -dir[2] * dir[0], -dir[2] * dir[1], 1.0 - dir[2] * dir[2] };
	normalize( nrm );
	tree->leaf_x[nl] = (float) t->p[0], tree->leaf_y[nl] = (float) t->p[1], tree->leaf_z[nl] = (float) t->p[2];
	tree->leaf_dirx[nl] = (float) dir[0], tree->leaf_diry[nl] = (float) dir[1];
	tree->leaf_dirz[nl] = (float) dir[2];
	tree->leaf_nx[nl] = (float) nrm[0], tree->leaf_ny[nl] = (float) nrm[1], tree->leaf_nz[nl] = (float) nrm[2];
}

sere_status sere_tree_grow( const sere_lsystem_params* params, sere_tree* tree )
{
	if ( tree == NULL || params == NULL )
	{
		return SERE_ERR_ARGUMENT;
	}
	memset( tree, 0, sizeof( *tree ) );
	if ( !( params->length > 0.0 ) || !isfinite( params->length ) || !( params->radius > 0.0 ) ||
		 !isfinite( params->radius ) || !( params->length_ratio > 0.0 && params->length_ratio <= 1.0 ) ||
		 !( params->radius_ratio > 0.0 && params->radius_ratio <= 1.0 ) || !isfinite( params->angle_deg ) ||
		 !isfinite( params->roll_deg ) || !isfinite( params->jitter_deg ) || !isfinite( params->leaf_droop_deg ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	char* s = NULL;
	int64_t n = 0;
	sere_status status = sere_lsystem_rewrite( params, &s, &n );
	if ( status != SERE_OK )
	{
		return status;
	}
	int64_t segments = 0, leaves = 0, depth = 0, max_depth = 0;
	for ( int64_t i = 0; i < n; ++i )
	{
		segments += s[i] == 'F';
		leaves += s[i] == 'L';
		depth += s[i] == '[' ? 1 : s[i] == ']' ? -1 : 0;
		max_depth = depth > max_depth ? depth : max_depth;
		if ( depth < 0 )
		{
			break;
		}
	}
	if ( depth != 0 )
	{
		free( s );
		return SERE_ERR_GEOMETRY;
	}
	if ( segments > INT32_MAX / 2 || leaves > INT32_MAX / 2 )
	{
		free( s );
		return SERE_ERR_CAPACITY;
	}
	float* seg = malloc( sizeof( float ) * 8 * (size_t) ( segments > 0 ? segments : 1 ) );
	float* leaf = malloc( sizeof( float ) * 9 * (size_t) ( leaves > 0 ? leaves : 1 ) );
	turtle* stack = malloc( sizeof( turtle ) * (size_t) ( max_depth + 1 ) );
	if ( seg == NULL || leaf == NULL || stack == NULL )
	{
		free( s ), free( seg ), free( leaf ), free( stack );
		return SERE_ERR_MEMORY;
	}
	const size_t S = (size_t) segments, L = (size_t) leaves;
	tree->x0 = seg, tree->y0 = seg + S, tree->z0 = seg + 2 * S, tree->r0 = seg + 3 * S;
	tree->x1 = seg + 4 * S, tree->y1 = seg + 5 * S, tree->z1 = seg + 6 * S, tree->r1 = seg + 7 * S;
	tree->leaf_x = leaf, tree->leaf_y = leaf + L, tree->leaf_z = leaf + 2 * L;
	tree->leaf_dirx = leaf + 3 * L, tree->leaf_diry = leaf + 4 * L, tree->leaf_dirz = leaf + 5 * L;
	tree->leaf_nx = leaf + 6 * L, tree->leaf_ny = leaf + 7 * L, tree->leaf_nz = leaf + 8 * L;
	tree->max_depth = (int32_t) max_depth;

	const double angle = params->angle_deg * DEG, roll = params->roll_deg * DEG, spread = params->jitter_deg * DEG;
	const double droop = params->leaf_droop_deg * DEG;
	turtle t = { { 0.0, 0.0, 0.0 },	 { 0.0, 0.0, 1.0 }, { 0.0, 1.0, 0.0 },
				 { -1.0, 0.0, 0.0 }, params->length,	params->radius };
	int32_t top = 0, ns = 0, nl = 0;
	for ( int64_t i = 0; i < n; ++i )
	{
		const double turn = spread * jitter( params->seed, i, 0 );
		switch ( s[i] )
		{
			case 'F':
			case 'f':
				ns += move_forward( &t, s[i] == 'F', params, tree, ns );
				break;
			case '+':
				rotate_pair( t.h, t.l, angle + turn );
				break;
			case '-':
				rotate_pair( t.h, t.l, -angle + turn );
				break;
			case '&':
				rotate_pair( t.h, t.u, -( angle + turn ) );
				break;
			case '^':
				rotate_pair( t.h, t.u, angle + turn );
				break;
			case '/':
				rotate_pair( t.l, t.u, roll + turn );
				break;
			case '\\':
				rotate_pair( t.l, t.u, -roll + turn );
				break;
			case '|':
				rotate_pair( t.h, t.l, 3.141592653589793 );
				break;
			case '!':
				t.length *= params->length_ratio;
				t.radius *= params->radius_ratio;
				break;
			case '[':
				stack[top++] = t;
				break;
			case ']':
				t = stack[--top];
				break;
			case 'L':
				add_leaf( &t, params->seed, i, droop, tree, nl++ );
				break;
			default:
				break;
		}
	}
	tree->segment_count = ns;
	tree->leaf_count = nl;
	free( stack );
	free( s );
	return SERE_OK;
}
