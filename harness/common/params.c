#define _POSIX_C_SOURCE 200809L
#include "common/params.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#ifndef SERE_DATA_DIR
#define SERE_DATA_DIR "/usr/local/share/sere"
#endif

/* Every kernel parameter's default is its kernel's *_default(); only the harness's own settings
 * get theirs here. */
sere_sim_params sere_sim_params_default( void )
{
	sere_sim_params p = {
		.layer = sere_layer_params_default(),
		.leaf = sere_leaf_params_default(),
		.crease = 0.0f,
		.curl = 0.0f,
		.face_down = 0,
		.seed = 1,
	};
	return p;
}

/* The osmosis mode is set through an int-sized row: paper 0, conservative 1. */
_Static_assert( sizeof( sere_osmosis_mode ) == sizeof( int ), "the conservative row writes an int" );
_Static_assert( SERE_OSMOSIS_PAPER == 0 && SERE_OSMOSIS_CONSERVATIVE == 1, "the conservative row is 0/1" );

#define AT( member ) offsetof( sere_sim_params, member )
#define ROW( name, symbol, type, member, lo, hi, doc )                                                                 \
	{                                                                                                                  \
		name, symbol, SERE_PARAM_##type, AT( member ), 0, lo, hi, doc                                                  \
	}

static const sere_param table[] = {
	ROW( "h_vein", "h_vein", DOUBLE, layer.h_vein, -1.0, 1.0, "Voronoi offset of vein triangles (Fig. 5e, Table 2)" ),
	ROW( "h_surf", "h_surf", DOUBLE, layer.h_surf, -1.0, 1.0, "Voronoi offset of the other triangles" ),
	ROW( "omega_vein", "ω_vein", DOUBLE, layer.omega_vein, 1e-6, 1e6,
		 "shortest-path weight of vein springs (Sec. 3.3)" ),
	ROW( "omega_surf", "ω_surf", DOUBLE, layer.omega_surf, 1e-6, 1e6, "shortest-path weight of surface springs" ),
	ROW( "D", "D", DOUBLE, layer.D, 1e-3, 100.0, "exponent of Jeong Eq. 1" ),
	/* Jeong Eq. 2's lower mass is also Sec. 5.1's shrinkage stop: one value in both structs */
	{ "m_min", "m_min", SERE_PARAM_DOUBLE, AT( layer.m_min ), AT( leaf.shrink.m_min ), 1e-6, 1e6,
	  "lower mass of Jeong Eq. 2; a spring stops shrinking below it (Sec. 5.1)" },
	ROW( "m_max", "m_max", DOUBLE, layer.m_max, 1e-6, 1e6, "upper mass of Jeong Eq. 2" ),
	ROW( "mu0", "μ₀", DOUBLE, layer.mu0, 0.0, 0.999, "initial water ratio w = mu0 m" ),
	ROW( "dt", "Δt", FLOAT, leaf.dt, 1e-6, 1.0, "time step" ),
	ROW( "gravity_x", "g_x", FLOAT, leaf.gravity[0], -1e3, 1e3, "gravity, x" ),
	ROW( "gravity_y", "g_y", FLOAT, leaf.gravity[1], -1e3, 1e3, "gravity, y" ),
	ROW( "gravity_z", "g_z", FLOAT, leaf.gravity[2], -1e3, 1e3, "gravity, z (the leaf's normal at rest is +z)" ),
	ROW( "damping", "", FLOAT, leaf.damping, 0.0, 1.0, "fraction of every velocity removed per frame (PBD damping)" ),
	ROW( "ground", "", FLOAT, leaf.ground, -INFINITY, 1e3, "height of the supporting plane (z); -inf for none" ),
	ROW( "lambda_min", "λ_min", DOUBLE, leaf.osmosis.lambda_min, 0.0, 1e6,
		 "diffusion coefficient at tau = 0 (Jeong Eq. 8)" ),
	ROW( "lambda_max", "λ_max", DOUBLE, leaf.osmosis.lambda_max, 0.0, 1e6, "diffusion coefficient at tau = 1" ),
	ROW( "conservative", "", BOOL, leaf.osmosis.mode, 0.0, 1.0,
		 "osmosis weights: 0 = paper (Jeong Eq. 8), 1 = conservative" ),
	ROW( "water_rate_t", "w_loss^T", DOUBLE, leaf.water_rate_t, -1e3, 1e3,
		 "signed water rate of the T layer (Table 2 w_loss^T; negative = losing)" ),
	ROW( "water_rate_v", "w_loss^V", DOUBLE, leaf.water_rate_v, -1e3, 1e3,
		 "signed water rate of the V layer (Table 2 w_loss^V)" ),
	ROW( "sigma_vein", "σ_v", DOUBLE, leaf.shrink.sigma_vein, -100.0, 100.0,
		 "shrinkage rate of vein springs (Jeong Eq. 12)" ),
	ROW( "sigma_surf", "σ_s", DOUBLE, leaf.shrink.sigma_surf, -100.0, 100.0,
		 "shrinkage rate of surface springs (Jeong Eq. 12)" ),
	ROW( "alpha", "α", DOUBLE, leaf.shrink.alpha, 0.1, 10.0, "exponent of Jeong Eq. 12" ),
	ROW( "min_length_ratio", "l_min", DOUBLE, leaf.shrink.min_length_ratio, 0.0, 1.0,
		 "springs stop shrinking below this fraction of their rest length" ),
	ROW( "stiffness", "k", FLOAT, leaf.pbd.stiffness, 0.0, 1.0, "PBD stiffness k (Sec. 5.2)" ),
	ROW( "strain_tolerance", "λ_C", FLOAT, leaf.pbd.tolerance, 1e-9, 1.0,
		 "the frame's stop: max |C + compliance/dt^2 lambda|/l (XPBD) or max |C/l| (lambda_C, compliance 0) below "
		 "it" ),
	ROW( "max_iterations", "", INT32, leaf.pbd.max_iterations, 1.0, 1e5, "PBD iteration cap" ),
	ROW( "compliance", "", FLOAT, leaf.pbd.compliance, 0.0, 1.0,
		 "XPBD compliance of the blade's springs (each frame an XPBD step); 0 = the paper's PBD (Table 1 rule)" ),
	ROW( "chebyshev_rho", "ρ", FLOAT, leaf.pbd.chebyshev_rho, 0.0, 0.99,
		 "Chebyshev semi-iteration of the XPBD sweeps (Wang 2015) with this spectral radius after chebyshev_delay "
		 "plain sweeps; 0 = off (0.9: a third to a half fewer sweeps, shapes not bitwise those of the plain sweeps)" ),
	ROW( "chebyshev_delay", "", INT32, leaf.pbd.chebyshev_delay, 2.0, 1e5,
		 "plain sweeps a frame before Chebyshev's first extrapolation (Wang 2015's S)" ),
	ROW( "pbd_stall", "", FLOAT, leaf.pbd.stall, 0.0, 0.999,
		 "0 = the paper's PBD stop; s > 0: also stop when 10 sweeps lower max |C/l| by less than the fraction s" ),
	ROW( "vein_compliance", "", FLOAT, leaf.vein_compliance, 0.0, 1e3,
		 "compliance weight of vein springs relative to the blade (stiffer below 1)" ),
	ROW( "voronoi_compliance", "", FLOAT, leaf.voronoi_compliance, 0.0, 1e6,
		 "compliance weight of the Voronoi layer's non-vein springs" ),
	ROW( "link_compliance", "", FLOAT, leaf.link_compliance, 0.0, 1e3,
		 "compliance weight of the L (thickness) springs relative to the blade" ),
	ROW( "friction_static", "", FLOAT, leaf.friction_static, 0.0, 10.0,
		 "static Coulomb friction of the ground contact" ),
	ROW( "friction_kinetic", "", FLOAT, leaf.friction_kinetic, 0.0, 10.0,
		 "kinetic Coulomb friction of the ground contact" ),
	ROW( "collisions", "", BOOL, leaf.collisions, 0.0, 1.0,
		 "self-collision pass of the triangle layer (1); it is off as well when collision_thickness = 0" ),
	ROW( "collision_thickness", "", FLOAT, leaf.collide.thickness, 0.0, 1.0,
		 "self-collision proximity distance (at rest when collision_scaling = 1)" ),
	ROW( "collision_scaling", "", BOOL, leaf.scale_thickness, 0.0, 1.0,
		 "collision thickness shrinks with the triangle layer (sum of T rest lengths / at rest) (1) or stays fixed "
		 "(0)" ),
	ROW( "restore_measured", "ĥ", BOOL, leaf.restore_measured, 0.0, 1.0,
		 "Jeong Eq. 14 with the measured thickness (1) or the rest h (0)" ),
	ROW( "soften", "", BOOL, leaf.soften, 0.0, 1.0, "scale PBD stiffness by relative water content (Sec. 7)" ),
	ROW( "local_stop", "", BOOL, leaf.local_stop, 0.0, 1.0,
		 "Sec. 6 stop where a layer runs dry: a particle whose neighbour in the other layer is dry keeps its water "
		 "(1)" ),
	ROW( "step_residual", "", BOOL, leaf.step_residual, 0.0, 1.0,
		 "measure each frame's XPBD step residual |h|/|grad C^T lambda| (Macklin et al. 2016 Eq. 8; stats.csv "
		 "step_primal), outside the timed parts (1)" ),
	ROW( "descent", "", BOOL, leaf.descent, 0.0, 1.0,
		 "each frame's step as a descent of the XPBD step's energy (a Newton step per particle, solve/vbd.h) to moves "
		 "below descent_tolerance: a rest state of the step (1), or XPBD (0)" ),
	ROW( "descent_tolerance", "", FLOAT, leaf.descent_tolerance, 1e-9, 0.1,
		 "the descent's stop: no particle moved farther than this fraction of the mean T spring in a sweep" ),
	ROW( "descent_rho", "", FLOAT, leaf.descent_rho, 0.0, 0.999,
		 "the descent's Chebyshev semi-iteration: spectral radius estimate rho (0: off)" ),
	ROW( "descent_delay", "", INT32, leaf.descent_delay, 2.0, 1e5,
		 "the descent's plain sweeps before the first Chebyshev extrapolation" ),
	ROW( "descent_warm", "", BOOL, leaf.descent_warm, 0.0, 1.0,
		 "the descent's sweeps begin at the prediction plus the last frame's correction (1) or at the prediction (0)" ),
	ROW( "crease", "", FLOAT, crease, -0.5, 0.5,
		 "initial shaping (Sec. 3.1): shorten Voronoi vein springs by this fraction" ),
	ROW( "curl", "", FLOAT, curl, -0.5, 0.5,
		 "initial shaping (Sec. 3.1): lengthen the other Voronoi springs by this fraction" ),
	ROW( "face_down", "", BOOL, face_down, 0.0, 1.0,
		 "1: the leaf lies with its Voronoi side (+h) down (mirrored through z): the faster-drying layer on top" ),
	ROW( "seed", "", UINT32, seed, 0.0, 4294967295.0, "sampling seed" ),
};

const sere_param* sere_params_table( int* count )
{
	*count = (int) ( sizeof( table ) / sizeof( table[0] ) );
	return table;
}

/* One member of any type the table holds, copied in and out of the struct by its size. */
typedef union member
{
	double d;
	float f;
	int32_t i;
	uint32_t u;
	int b;
} member;

static size_t member_size( sere_param_type type )
{
	return type == SERE_PARAM_DOUBLE ? sizeof( double ) : type == SERE_PARAM_BOOL ? sizeof( int ) : sizeof( float );
}

static double read_at( const sere_sim_params* params, size_t offset, sere_param_type type )
{
	member m;
	memcpy( &m, (const char*) params + offset, member_size( type ) );
	return type == SERE_PARAM_DOUBLE   ? m.d
		   : type == SERE_PARAM_FLOAT  ? (double) m.f
		   : type == SERE_PARAM_INT32  ? (double) m.i
		   : type == SERE_PARAM_UINT32 ? (double) m.u
									   : (double) m.b;
}

/* value is in range and whole where the type is: every conversion below is exact but the
 * float's, which rounds the parsed double once, as the kernels always received it. */
static void write_at( sere_sim_params* params, size_t offset, sere_param_type type, double value )
{
	member m;
	if ( type == SERE_PARAM_DOUBLE )
	{
		m.d = value;
	}
	else if ( type == SERE_PARAM_FLOAT )
	{
		m.f = (float) value;
	}
	else if ( type == SERE_PARAM_INT32 )
	{
		m.i = (int32_t) value;
	}
	else if ( type == SERE_PARAM_UINT32 )
	{
		m.u = (uint32_t) value;
	}
	else
	{
		m.b = value != 0.0;
	}
	memcpy( (char*) params + offset, &m, member_size( type ) );
}

double sere_params_get( const sere_sim_params* params, const sere_param* row )
{
	return read_at( params, row->offset, row->type );
}

static const sere_param* find_key( const char* name, size_t length )
{
	for ( size_t i = 0; i < sizeof( table ) / sizeof( table[0] ); ++i )
	{
		if ( strlen( table[i].name ) == length && strncmp( table[i].name, name, length ) == 0 )
		{
			return table + i;
		}
	}
	return NULL;
}

static sere_status parse_value( const sere_param* key, const char* text, double* value, char* err, size_t err_size )
{
	char* end = NULL;
	errno = 0;
	double v = strtod( text, &end );
	while ( end != NULL && ( *end == ' ' || *end == '\t' || *end == '\r' || *end == '\n' ) )
	{
		++end;
	}
	if ( end == text || end == NULL || *end != '\0' || errno == ERANGE || isnan( v ) )
	{
		snprintf( err, err_size, "%s: '%s' is not a number", key->name, text );
		return SERE_ERR_PARSE;
	}
	if ( v < key->lo || v > key->hi )
	{
		snprintf( err, err_size, "%s = %g is out of range [%g, %g]", key->name, v, key->lo, key->hi );
		return SERE_ERR_ARGUMENT;
	}
	if ( key->type != SERE_PARAM_DOUBLE && key->type != SERE_PARAM_FLOAT && v != floor( v ) )
	{
		snprintf( err, err_size, "%s must be a whole number, not %g", key->name, v );
		return SERE_ERR_ARGUMENT;
	}
	*value = v;
	return SERE_OK;
}

sere_status sere_params_set( sere_sim_params* params, const char* assignment, char* err, size_t err_size )
{
	const char* eq = strchr( assignment, '=' );
	if ( eq == NULL )
	{
		snprintf( err, err_size, "expected key=value, got '%s'", assignment );
		return SERE_ERR_PARSE;
	}
	const char* name = assignment;
	size_t length = (size_t) ( eq - assignment );
	while ( length > 0 && ( name[length - 1] == ' ' || name[length - 1] == '\t' ) )
	{
		--length;
	}
	const sere_param* key = find_key( name, length );
	if ( key == NULL )
	{
		snprintf( err, err_size, "unknown parameter '%.*s' (sere run --help lists them)", (int) length, name );
		return SERE_ERR_ARGUMENT;
	}
	const char* text = eq + 1;
	while ( *text == ' ' || *text == '\t' )
	{
		++text;
	}
	double value;
	sere_status status = parse_value( key, text, &value, err, err_size );
	if ( status != SERE_OK )
	{
		return status;
	}
	write_at( params, key->offset, key->type, value );
	if ( key->also != 0 )
	{
		write_at( params, key->also, key->type, value );
	}
	if ( params->layer.m_max < params->layer.m_min )
	{
		snprintf( err, err_size, "m_max (%g) must not be below m_min (%g)", params->layer.m_max, params->layer.m_min );
		return SERE_ERR_ARGUMENT;
	}
	return SERE_OK;
}

static int file_exists( const char* path )
{
	struct stat info;
	return stat( path, &info ) == 0 && S_ISREG( info.st_mode );
}

sere_status sere_data_find( const char* relative, char* path, size_t path_size )
{
	/* SERE_DATA first; then PREFIX/share/sere beside the running binary PREFIX/bin/sere, found
	 * from /proc/self/exe at run time so that an installed tree still works after it is moved;
	 * then ./data (a source checkout); then the prefix compiled in. */
	char exe[4096], beside[4096 + 32] = "";
	ssize_t length = readlink( "/proc/self/exe", exe, sizeof( exe ) - 1 );
	if ( length > 0 )
	{
		exe[length] = '\0';
		char* slash = strrchr( exe, '/' );
		if ( slash != NULL )
		{
			*slash = '\0';
			snprintf( beside, sizeof( beside ), "%s/../share/sere", exe );
		}
	}
	const char* roots[] = { getenv( "SERE_DATA" ), beside[0] != '\0' ? beside : NULL, "data", SERE_DATA_DIR };
	for ( size_t i = 0; i < sizeof( roots ) / sizeof( roots[0] ); ++i )
	{
		if ( roots[i] == NULL )
		{
			continue;
		}
		snprintf( path, path_size, "%s/%s", roots[i], relative );
		if ( file_exists( path ) )
		{
			return SERE_OK;
		}
	}
	return SERE_ERR_IO;
}

const char* sere_data_resolve( const char* path, char* buffer, size_t size )
{
	FILE* f = fopen( path, "rb" );
	if ( f != NULL )
	{
		fclose( f );
		return path;
	}
	return path[0] != '/' && sere_data_find( path, buffer, size ) == SERE_OK ? buffer : path;
}

sere_status sere_params_load_preset( sere_sim_params* params, const char* name_or_path, char* err, size_t err_size )
{
	char path[4096];
	if ( file_exists( name_or_path ) )
	{
		snprintf( path, sizeof( path ), "%s", name_or_path );
	}
	else
	{
		char relative[512];
		snprintf( relative, sizeof( relative ), "presets/%s.preset", name_or_path );
		if ( sere_data_find( relative, path, sizeof( path ) ) != 0 )
		{
			snprintf(
				err, err_size,
				"unknown preset '%s' (known: maple-green, maple-red, plane-tree, wisteria, grass, or a file path)",
				name_or_path );
			return SERE_ERR_IO;
		}
	}
	FILE* f = fopen( path, "r" );
	if ( f == NULL )
	{
		snprintf( err, err_size, "%s: %s", path, strerror( errno ) );
		return SERE_ERR_IO;
	}
	/* Lines of any length: a long comment stays a comment, and a line number is a line's. */
	char* line = NULL;
	size_t capacity = 0;
	ssize_t got;
	int number = 0;
	while ( ( got = getline( &line, &capacity, f ) ) >= 0 )
	{
		++number;
		if ( memchr( line, '\0', (size_t) got ) != NULL )
		{
			snprintf( err, err_size, "%s:%d: a NUL byte (this is not a text file)", path, number );
			free( line );
			fclose( f );
			return SERE_ERR_PARSE;
		}
		char* hash = strchr( line, '#' );
		if ( hash != NULL )
		{
			*hash = '\0';
		}
		char* start = line;
		while ( *start == ' ' || *start == '\t' )
		{
			++start;
		}
		size_t length = strlen( start );
		while ( length > 0 && ( start[length - 1] == '\n' || start[length - 1] == '\r' || start[length - 1] == ' ' ||
								start[length - 1] == '\t' ) )
		{
			start[--length] = '\0';
		}
		if ( length == 0 )
		{
			continue;
		}
		char message[512];
		sere_status status = sere_params_set( params, start, message, sizeof( message ) );
		if ( status != SERE_OK )
		{
			snprintf( err, err_size, "%s:%d: %s", path, number, message );
			free( line );
			fclose( f );
			return status;
		}
	}
	int failed = ferror( f );
	int error = errno;
	free( line );
	fclose( f );
	if ( failed )
	{
		snprintf( err, err_size, "%s: cannot read: %s", path, strerror( error ) );
		return SERE_ERR_IO;
	}
	return SERE_OK;
}

sere_status sere_params_apply( sere_sim_params* params, const char* preset, const char* const* sets, int set_count,
							   char* err, size_t err_size )
{
	sere_status status = preset != NULL ? sere_params_load_preset( params, preset, err, err_size ) : SERE_OK;
	for ( int k = 0; k < set_count && status == SERE_OK; ++k )
	{
		status = sere_params_set( params, sets[k], err, err_size );
	}
	/* a descent needs every spring's stiffness finite (solve/vbd.h); XPBD takes a rigid class */
	const sere_leaf_params* leaf = &params->leaf;
	const struct
	{
		const char* key;
		float weight;
	} weights[] = { { "vein_compliance", leaf->vein_compliance },
					{ "voronoi_compliance", leaf->voronoi_compliance },
					{ "link_compliance", leaf->link_compliance } };
	for ( size_t k = 0; k < 3 && status == SERE_OK && leaf->descent && leaf->pbd.compliance > 0.0f; ++k )
	{
		if ( weights[k].weight == 0.0f )
		{
			snprintf( err, err_size,
					  "%s = 0 makes those springs rigid, which the descent step cannot take: set it above 0, or "
					  "descent=0 for the XPBD step",
					  weights[k].key );
			status = SERE_ERR_ARGUMENT;
		}
	}
	return status;
}

/* The shortest text that reads back as the same value of row's type: a float row writes
 * "0.002", not the double nearest 0.002f. */
static void format_value( const sere_param* row, double value, char* text, size_t size )
{
	if ( row->type != SERE_PARAM_FLOAT && row->type != SERE_PARAM_DOUBLE )
	{
		snprintf( text, size, "%.0f", value );
		return;
	}
	for ( int digits = 1; digits <= 17; ++digits )
	{
		snprintf( text, size, "%.*g", digits, value );
		double back = strtod( text, NULL );
		if ( row->type == SERE_PARAM_FLOAT ? (float) back == (float) value : back == value )
		{
			return;
		}
	}
}

double sere_params_decimal( float value )
{
	static const sere_param as_float = { "", "", SERE_PARAM_FLOAT, 0, 0, 0.0, 0.0, "" };
	char text[64];
	format_value( &as_float, value, text, sizeof( text ) );
	return isfinite( value ) ? strtod( text, NULL ) : (double) value;
}

void sere_params_print_json( const sere_sim_params* params, FILE* f, const char* indent )
{
	size_t count = sizeof( table ) / sizeof( table[0] );
	for ( size_t i = 0; i < count; ++i )
	{
		double value = sere_params_get( params, table + i );
		const char* end = i + 1 < count ? ",\n" : "\n";
		/* JSON has no infinity: the ground's −inf ("no plane") is written as null */
		char text[64] = "null";
		if ( isfinite( value ) )
		{
			format_value( table + i, value, text, sizeof( text ) );
		}
		fprintf( f, "%s\"%s\": %s%s", indent, table[i].name, text, end );
	}
}

static const char* type_name( sere_param_type type )
{
	switch ( type )
	{
		case SERE_PARAM_DOUBLE:
			return "double";
		case SERE_PARAM_FLOAT:
			return "float";
		case SERE_PARAM_INT32:
			return "int32";
		case SERE_PARAM_UINT32:
			return "uint32";
		case SERE_PARAM_BOOL:
			return "bool";
	}
	return "?";
}

void sere_params_describe( FILE* f )
{
	sere_sim_params defaults = sere_sim_params_default();
	for ( size_t i = 0; i < sizeof( table ) / sizeof( table[0] ); ++i )
	{
		const sere_param* row = table + i;
		char value[64];
		format_value( row, sere_params_get( &defaults, row ), value, sizeof( value ) );
		fprintf( f, "  %-20s %s", row->name, row->doc );
		fprintf( f, "\n  %-20s %s%s%s, default %s, range [%g, %g]\n", "", row->symbol,
				 row->symbol[0] != '\0' ? ", " : "", type_name( row->type ), value, row->lo, row->hi );
	}
}
