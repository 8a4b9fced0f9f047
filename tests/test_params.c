/* The parameter table (harness/common/params.c): every row reaches the struct member it names,
 * round-trips through --set and summary.json, refuses values out of its range, and takes its
 * default from the kernel's own *_default(). */
#define _POSIX_C_SOURCE 200809L
#include "common/params.h"
#include "drying/layers.h"
#include "drying/leaf.h"
#include "drying/osmosis.h"
#include "solve/collide.h"
#include "solve/pbd.h"

#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static size_t type_size( sere_param_type type )
{
	return type == SERE_PARAM_DOUBLE ? sizeof( double ) : type == SERE_PARAM_BOOL ? sizeof( int ) : sizeof( float );
}

/* A value in row's range other than its default, exact in its type. */
static double other_value( const sere_param* row, double fallback )
{
	if ( row->type == SERE_PARAM_BOOL )
	{
		return fallback != 0.0 ? 0.0 : 1.0;
	}
	double lo = isfinite( row->lo ) ? row->lo : -1.0;
	double v = row->type == SERE_PARAM_INT32 || row->type == SERE_PARAM_UINT32 ? floor( 0.5 * ( lo + row->hi ) )
																			   : lo + 0.375 * ( row->hi - lo );
	if ( v == fallback )
	{
		v = row->hi;
	}
	return row->type == SERE_PARAM_FLOAT ? (double) (float) v : v;
}

/* The text after "name": in a summary block, or NULL. */
static const char* json_value( const char* json, const char* name )
{
	char key[96];
	snprintf( key, sizeof( key ), "\"%s\": ", name );
	const char* at = strstr( json, key );
	return at != NULL ? at + strlen( key ) : NULL;
}

Test( params, rows_are_distinct_and_inside_the_struct )
{
	int count;
	const sere_param* table = sere_params_table( &count );
	cr_assert_gt( count, 40 );
	for ( int i = 0; i < count; ++i )
	{
		const sere_param* row = table + i;
		cr_expect( row->offset + type_size( row->type ) <= sizeof( sere_sim_params ), "%s lies outside", row->name );
		cr_expect( row->lo <= row->hi, "%s: empty range", row->name );
		cr_expect( row->doc[0] != '\0', "%s: no documentation", row->name );
		for ( int j = 0; j < i; ++j )
		{
			cr_expect( strcmp( row->name, table[j].name ) != 0, "%s appears twice", row->name );
			cr_expect( row->offset != table[j].offset, "%s and %s set the same member", row->name, table[j].name );
		}
	}
}

/* Every byte of the builder's struct and of the harness's own settings is some row's: a member
 * added there without a row fails here. */
Test( params, rows_cover_the_builder_and_harness_members )
{
	int count;
	const sere_param* table = sere_params_table( &count );
	unsigned char covered[sizeof( sere_sim_params )] = { 0 };
	for ( int i = 0; i < count; ++i )
	{
		memset( covered + table[i].offset, 1, type_size( table[i].type ) );
	}
	size_t layer = offsetof( sere_sim_params, layer );
	for ( size_t b = layer; b < layer + sizeof( sere_layer_params ); ++b )
	{
		cr_expect( covered[b], "byte %zu of sere_layer_params has no row", b - layer );
	}
	for ( size_t b = offsetof( sere_sim_params, crease ); b < offsetof( sere_sim_params, seed ) + sizeof( uint32_t );
		  ++b )
	{
		cr_expect( covered[b], "byte %zu of the harness settings has no row", b );
	}
	/* the leaf members the harness always set (the keys of every preset and summary before the
	 * table): each still has its row */
	static const char* const leaf_keys[] = {
		"dt",
		"gravity_x",
		"gravity_y",
		"gravity_z",
		"damping",
		"ground",
		"lambda_min",
		"lambda_max",
		"conservative",
		"water_rate_t",
		"water_rate_v",
		"sigma_vein",
		"sigma_surf",
		"alpha",
		"min_length_ratio",
		"stiffness",
		"strain_tolerance",
		"max_iterations",
		"compliance",
		"chebyshev_rho",
		"chebyshev_delay",
		"pbd_stall",
		"vein_compliance",
		"voronoi_compliance",
		"link_compliance",
		"friction_static",
		"friction_kinetic",
		"collision_thickness",
		"collision_scaling",
		"restore_measured",
		"soften",
		"local_stop",
	};
	for ( size_t k = 0; k < sizeof( leaf_keys ) / sizeof( leaf_keys[0] ); ++k )
	{
		int found = 0;
		for ( int i = 0; i < count; ++i )
		{
			found |= strcmp( table[i].name, leaf_keys[k] ) == 0 &&
					 table[i].offset >= offsetof( sere_sim_params, leaf ) &&
					 table[i].offset < offsetof( sere_sim_params, leaf ) + sizeof( sere_leaf_params );
		}
		cr_expect( found, "%s has no row in the leaf's struct", leaf_keys[k] );
	}
}

Test( params, defaults_are_the_kernel_defaults )
{
	sere_sim_params d = sere_sim_params_default();
	sere_leaf_params leaf = sere_leaf_params_default();
	sere_layer_params layer = sere_layer_params_default();
	sere_pbd_params pbd = sere_pbd_params_default();
	int count;
	const sere_param* table = sere_params_table( &count );
	sere_sim_params kernel = d;
	kernel.leaf = leaf;
	kernel.layer = layer;
	for ( int i = 0; i < count; ++i )
	{
		double a = sere_params_get( &d, table + i ), b = sere_params_get( &kernel, table + i );
		cr_expect( a == b || ( isnan( a ) && isnan( b ) ), "%s: default %g, the kernel's %g", table[i].name, a, b );
	}
	cr_expect_eq( d.leaf.pbd.stall, pbd.stall, "the stall rule's default is the PBD solver's" );
	cr_expect_eq( d.leaf.pbd.stall, 0.0f, "the paper's stop by default" );
	cr_expect_eq( d.leaf.osmosis.lambda_min, sere_osmosis_params_default().lambda_min );
	cr_expect_eq( d.layer.m_min, d.leaf.shrink.m_min, "m_min is one value in both structs" );
	cr_expect_eq( d.leaf.collide.iterations, sere_collide_params_default().iterations );
}

/* Runs check on every row of the table with the default parameters, fresh for each row. */
static void each_row( void ( *check )( const sere_param* row, sere_sim_params* p ) )
{
	int count;
	const sere_param* table = sere_params_table( &count );
	for ( int i = 0; i < count; ++i )
	{
		sere_sim_params p = sere_sim_params_default();
		check( table + i, &p );
	}
}

static void round_trip( const sere_param* row, sere_sim_params* p )
{
	/* m_min may not pass m_max (1 by default): its lower bound instead */
	double value = strcmp( row->name, "m_min" ) == 0 ? row->lo : other_value( row, sere_params_get( p, row ) );
	char assignment[128], err[256] = "";
	snprintf( assignment, sizeof( assignment ), "%s=%.17g", row->name, value );
	cr_assert_eq( sere_params_set( p, assignment, err, sizeof( err ) ), 0, "%s: %s", assignment, err );
	cr_expect_eq( sere_params_get( p, row ), value, "%s: read back %.17g", assignment, sere_params_get( p, row ) );
	if ( row->also != 0 )
	{
		sere_param second = *row;
		second.offset = row->also;
		cr_expect_eq( sere_params_get( p, &second ), value, "%s: its second place differs", row->name );
	}

	char* json = NULL;
	size_t size = 0;
	FILE* f = open_memstream( &json, &size );
	cr_assert_not_null( f );
	sere_params_print_json( p, f, "" );
	fclose( f );
	const char* text = json_value( json, row->name );
	cr_assert_not_null( text, "%s missing from the summary", row->name );
	char* end = NULL;
	strtod( text, &end );
	cr_expect( end != text, "%s: '%.20s' is not a number", row->name, text );
	sere_sim_params again = sere_sim_params_default();
	char reset[128];
	snprintf( reset, sizeof( reset ), "%s=%.*s", row->name, (int) ( end - text ), text );
	cr_expect_eq( sere_params_set( &again, reset, err, sizeof( err ) ), 0, "%s: %s", reset, err );
	cr_expect_eq( sere_params_get( &again, row ), value, "%s: the summary's %s reads back differently", row->name,
				  reset );
	free( json );
}

Test( params, every_row_round_trips_through_set_and_summary )
{
	each_row( round_trip );
}

static void refuse_outside_range( const sere_param* row, sere_sim_params* p )
{
	char assignment[128], err[256] = "";
	double outside = row->hi + ( fabs( row->hi ) + 1.0 );
	snprintf( assignment, sizeof( assignment ), "%s=%.17g", row->name, outside );
	cr_expect_eq( sere_params_set( p, assignment, err, sizeof( err ) ), SERE_ERR_ARGUMENT, "%s accepted", assignment );
	cr_expect( strstr( err, row->name ) != NULL && strstr( err, "out of range" ) != NULL, "%s: '%s'", assignment, err );
	if ( isfinite( row->lo ) )
	{
		snprintf( assignment, sizeof( assignment ), "%s=%.17g", row->name, row->lo - ( fabs( row->lo ) + 1.0 ) );
		cr_expect_eq( sere_params_set( p, assignment, err, sizeof( err ) ), SERE_ERR_ARGUMENT, "%s accepted",
					  assignment );
	}
	if ( row->type != SERE_PARAM_DOUBLE && row->type != SERE_PARAM_FLOAT )
	{
		snprintf( assignment, sizeof( assignment ), "%s=%g", row->name, row->lo + 0.5 );
		cr_expect_eq( sere_params_set( p, assignment, err, sizeof( err ) ), SERE_ERR_ARGUMENT, "%s accepted",
					  assignment );
		cr_expect( strstr( err, "whole number" ) != NULL, "%s: '%s'", assignment, err );
	}
}

Test( params, ranges_refuse_with_the_key_and_range )
{
	each_row( refuse_outside_range );
	char err[256];
	sere_sim_params p = sere_sim_params_default();
	cr_expect_eq( sere_params_set( &p, "no_such_key=1", err, sizeof( err ) ), SERE_ERR_ARGUMENT );
	cr_expect( strstr( err, "no_such_key" ) != NULL, "%s", err );
	cr_expect_eq( sere_params_set( &p, "dt=fast", err, sizeof( err ) ), SERE_ERR_PARSE );
	cr_expect( strstr( err, "not a number" ) != NULL, "%s", err );
}

Test( params, help_lists_every_row_with_default_range_and_symbol )
{
	char* text = NULL;
	size_t size = 0;
	FILE* f = open_memstream( &text, &size );
	cr_assert_not_null( f );
	sere_params_describe( f );
	fclose( f );
	int count;
	const sere_param* table = sere_params_table( &count );
	for ( int i = 0; i < count; ++i )
	{
		char line[96];
		snprintf( line, sizeof( line ), "  %-20s %s", table[i].name, table[i].doc );
		const char* at = strstr( text, line );
		cr_expect_not_null( at, "--help misses %s", table[i].name );
		if ( at != NULL )
		{
			const char* next = strchr( strchr( at, '\n' ) + 1, '\n' );
			cr_assert_not_null( next );
			char detail[1024];
			snprintf( detail, sizeof( detail ), "%.*s", (int) ( next - at ), at );
			cr_expect( strstr( detail, "default " ) != NULL && strstr( detail, "range [" ) != NULL &&
						   strstr( detail, table[i].symbol ) != NULL,
					   "%s: '%s'", table[i].name, detail );
		}
	}
	cr_expect( strstr( text, "λ_C, float, default 0.001" ) != NULL, "the paper's symbol and the float's default" );
	free( text );
}

/* Every shipped preset sets only table keys within their ranges. */
Test( params, presets_load )
{
	static const char* const presets[] = { "maple-green", "maple-red", "plane-tree", "wisteria", "grass" };
	for ( size_t k = 0; k < sizeof( presets ) / sizeof( presets[0] ); ++k )
	{
		sere_sim_params p = sere_sim_params_default();
		char err[512] = "";
		cr_expect_eq( sere_params_load_preset( &p, presets[k], err, sizeof( err ) ), 0, "%s: %s", presets[k], err );
		cr_expect_eq( p.layer.m_min, p.leaf.shrink.m_min, "%s: m_min in both structs", presets[k] );
	}
}
