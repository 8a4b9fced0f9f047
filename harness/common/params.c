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

sere_sim_params sere_sim_params_default( void )
{
	sere_sim_params p = {
		.layer = sere_layer_params_default(),
		.dt = 0.002,
		.gravity = { 0.0, 0.0, 0.0 },
		.damping = 0.1,
		.ground = -INFINITY,
		.lambda_min = 0.1,
		.lambda_max = 0.1,
		.water_rate_t = -0.1,
		.water_rate_v = -0.1,
		.sigma_vein = 0.5,
		.sigma_surf = 0.5,
		.alpha = 1.3,
		.min_length_ratio = 0.2,
		.stiffness = 1.0,
		.strain_tolerance = 1e-3,
		.compliance = 4e-6,
		.vein_compliance = 0.1,
		.voronoi_compliance = 1.0,
		.link_compliance = 1.0,
		.face_down = 0,
		.local_stop = 0,
		.friction_static = 0.8,
		.friction_kinetic = 0.6,
		.max_iterations = 200,
		.chebyshev_rho = 0.0,
		.pbd_stall = 0.0,
		.collision_thickness = 0.004,
		.collision_scaling = 1,
		.restore_measured = 1,
		.conservative = 0,
		.soften = 0,
		.crease = 0.0,
		.curl = 0.0,
		.seed = 1,
	};
	return p;
}

typedef struct key_info
{
	const char* name;
	size_t offset;
	double lo, hi;
	int integer;
	const char* help;
} key_info;

#define KEY( field, lo, hi, integer, help )                                                                            \
	{                                                                                                                  \
#field, offsetof( sere_sim_params, field ), lo, hi, integer, help                                              \
	}
#define LKEY( name, field, lo, hi, help )                                                                              \
	{                                                                                                                  \
		name, offsetof( sere_sim_params, layer ) + offsetof( sere_layer_params, field ), lo, hi, 0, help               \
	}

static const key_info keys[] = {
	LKEY( "h_vein", h_vein, -1.0, 1.0, "Voronoi offset of vein triangles (Fig. 5e, Table 2)" ),
	LKEY( "h_surf", h_surf, -1.0, 1.0, "Voronoi offset of the other triangles" ),
	LKEY( "omega_vein", omega_vein, 1e-6, 1e6, "shortest-path weight of vein springs (Sec. 3.3)" ),
	LKEY( "omega_surf", omega_surf, 1e-6, 1e6, "shortest-path weight of surface springs" ),
	LKEY( "D", D, 1e-3, 100.0, "exponent of Jeong Eq. 1" ),
	LKEY( "m_min", m_min, 1e-6, 1e6, "lower mass of Jeong Eq. 2" ),
	LKEY( "m_max", m_max, 1e-6, 1e6, "upper mass of Jeong Eq. 2" ),
	LKEY( "mu0", mu0, 0.0, 0.999, "initial water ratio w = mu0 m" ),
	KEY( dt, 1e-6, 1.0, 0, "time step" ),
	{ "gravity_x", offsetof( sere_sim_params, gravity ), -1e3, 1e3, 0, "gravity, x" },
	{ "gravity_y", offsetof( sere_sim_params, gravity ) + sizeof( double ), -1e3, 1e3, 0, "gravity, y" },
	{ "gravity_z", offsetof( sere_sim_params, gravity ) + 2 * sizeof( double ), -1e3, 1e3, 0,
	  "gravity, z (the leaf's normal at rest is +z)" },
	KEY( damping, 0.0, 1.0, 0, "fraction of every velocity removed per frame (PBD damping)" ),
	KEY( ground, -INFINITY, 1e3, 0, "height of the supporting plane (z); -inf for none" ),
	KEY( lambda_min, 0.0, 1e6, 0, "diffusion coefficient at tau = 0 (Jeong Eq. 8)" ),
	KEY( lambda_max, 0.0, 1e6, 0, "diffusion coefficient at tau = 1" ),
	KEY( water_rate_t, -1e3, 1e3, 0, "signed water rate of the T layer (Table 2 w_loss^T; negative = losing)" ),
	KEY( water_rate_v, -1e3, 1e3, 0, "signed water rate of the V layer (Table 2 w_loss^V)" ),
	KEY( sigma_vein, -100.0, 100.0, 0, "shrinkage rate of vein springs (Jeong Eq. 12)" ),
	KEY( sigma_surf, -100.0, 100.0, 0, "shrinkage rate of surface springs (Jeong Eq. 12)" ),
	KEY( alpha, 0.1, 10.0, 0, "exponent of Jeong Eq. 12" ),
	KEY( min_length_ratio, 0.0, 1.0, 0, "springs stop shrinking below this fraction of their rest length" ),
	KEY( stiffness, 0.0, 1.0, 0, "PBD stiffness k (Sec. 5.2)" ),
	KEY( strain_tolerance, 1e-9, 1.0, 0,
		 "the frame's stop: max |C + compliance/dt^2 lambda|/l (XPBD) or max |C/l| (lambda_C, compliance 0) below it" ),
	KEY( compliance, 0.0, 1.0, 0,
		 "XPBD compliance of the blade's springs (each frame an XPBD step); 0 = the paper's PBD (Table 1 rule)" ),
	KEY( vein_compliance, 0.0, 1e3, 0, "compliance weight of vein springs relative to the blade (stiffer below 1)" ),
	KEY( voronoi_compliance, 0.0, 1e6, 0, "compliance weight of the Voronoi layer's non-vein springs" ),
	KEY( local_stop, 0.0, 1.0, 1,
		 "Sec. 6 stop where a layer runs dry: a particle whose neighbour in the other layer is dry keeps its water "
		 "(1)" ),
	KEY( face_down, 0.0, 1.0, 1,
		 "1: the leaf lies with its Voronoi side (+h) down (mirrored through z): the faster-drying layer on top" ),
	KEY( link_compliance, 0.0, 1e3, 0, "compliance weight of the L (thickness) springs relative to the blade" ),
	KEY( friction_static, 0.0, 10.0, 0, "static Coulomb friction of the ground contact" ),
	KEY( friction_kinetic, 0.0, 10.0, 0, "kinetic Coulomb friction of the ground contact" ),
	KEY( max_iterations, 1.0, 1e5, 1, "PBD iteration cap" ),
	KEY( chebyshev_rho, 0.0, 0.99, 0,
		 "Chebyshev semi-iteration of the XPBD sweeps (Wang 2015) with this spectral radius after 5 plain sweeps; 0 = "
		 "off (0.9: a third to a half fewer sweeps, shapes not bitwise those of the plain sweeps)" ),
	KEY( pbd_stall, 0.0, 0.999, 0,
		 "0 = the paper's PBD stop; s > 0: also stop when 10 sweeps lower max |C/l| by less than the fraction s" ),
	KEY( collision_thickness, 0.0, 1.0, 0, "self-collision proximity distance (at rest when collision_scaling = 1)" ),
	KEY( collision_scaling, 0.0, 1.0, 1,
		 "collision thickness shrinks with the triangle layer (sum of T rest lengths / at rest) (1) or stays fixed "
		 "(0)" ),
	KEY( restore_measured, 0.0, 1.0, 1, "Jeong Eq. 14 with the measured thickness (1) or the rest h (0)" ),
	KEY( conservative, 0.0, 1.0, 1, "osmosis weights: 0 = paper (Jeong Eq. 8), 1 = conservative" ),
	KEY( soften, 0.0, 1.0, 1, "scale PBD stiffness by relative water content (Sec. 7)" ),
	KEY( crease, -0.5, 0.5, 0, "initial shaping (Sec. 3.1): shorten Voronoi vein springs by this fraction" ),
	KEY( curl, -0.5, 0.5, 0, "initial shaping (Sec. 3.1): lengthen the other Voronoi springs by this fraction" ),
	KEY( seed, 0.0, 4294967295.0, 1, "sampling seed" ),
};

static const key_info* find_key( const char* name, size_t length )
{
	for ( size_t i = 0; i < sizeof( keys ) / sizeof( keys[0] ); ++i )
	{
		if ( strlen( keys[i].name ) == length && strncmp( keys[i].name, name, length ) == 0 )
		{
			return keys + i;
		}
	}
	return NULL;
}

static int parse_value( const key_info* key, const char* text, double* value, char* err, size_t err_size )
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
		return -1;
	}
	if ( v < key->lo || v > key->hi )
	{
		snprintf( err, err_size, "%s = %g is out of range [%g, %g]", key->name, v, key->lo, key->hi );
		return -1;
	}
	if ( key->integer && v != floor( v ) )
	{
		snprintf( err, err_size, "%s must be a whole number, not %g", key->name, v );
		return -1;
	}
	*value = v;
	return 0;
}

int sere_params_set( sere_sim_params* params, const char* assignment, char* err, size_t err_size )
{
	const char* eq = strchr( assignment, '=' );
	if ( eq == NULL )
	{
		snprintf( err, err_size, "expected key=value, got '%s'", assignment );
		return -1;
	}
	const char* name = assignment;
	size_t length = (size_t) ( eq - assignment );
	while ( length > 0 && ( name[length - 1] == ' ' || name[length - 1] == '\t' ) )
	{
		--length;
	}
	const key_info* key = find_key( name, length );
	if ( key == NULL )
	{
		snprintf( err, err_size, "unknown parameter '%.*s' (sere run --help lists them)", (int) length, name );
		return -1;
	}
	const char* text = eq + 1;
	while ( *text == ' ' || *text == '\t' )
	{
		++text;
	}
	double value;
	if ( parse_value( key, text, &value, err, err_size ) != 0 )
	{
		return -1;
	}
	memcpy( (char*) params + key->offset, &value, sizeof( double ) );
	if ( params->layer.m_max < params->layer.m_min )
	{
		snprintf( err, err_size, "m_max (%g) must not be below m_min (%g)", params->layer.m_max, params->layer.m_min );
		return -1;
	}
	return 0;
}

static int file_exists( const char* path )
{
	struct stat info;
	return stat( path, &info ) == 0 && S_ISREG( info.st_mode );
}

int sere_data_path( const char* relative, char* path, size_t path_size )
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
			return 0;
		}
	}
	return -1;
}

int sere_params_load_preset( sere_sim_params* params, const char* name_or_path, char* err, size_t err_size )
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
		if ( sere_data_path( relative, path, sizeof( path ) ) != 0 )
		{
			snprintf(
				err, err_size,
				"unknown preset '%s' (known: maple-green, maple-red, plane-tree, wisteria, grass, or a file path)",
				name_or_path );
			return -1;
		}
	}
	FILE* f = fopen( path, "r" );
	if ( f == NULL )
	{
		snprintf( err, err_size, "%s: %s", path, strerror( errno ) );
		return -1;
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
			return -1;
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
		if ( sere_params_set( params, start, message, sizeof( message ) ) != 0 )
		{
			snprintf( err, err_size, "%s:%d: %s", path, number, message );
			free( line );
			fclose( f );
			return -1;
		}
	}
	int failed = ferror( f );
	int error = errno;
	free( line );
	fclose( f );
	if ( failed )
	{
		snprintf( err, err_size, "%s: cannot read: %s", path, strerror( error ) );
		return -1;
	}
	return 0;
}

int sere_params_apply( sere_sim_params* params, const char* preset, const char* const* sets, int set_count, char* err,
					   size_t err_size )
{
	if ( preset != NULL && sere_params_load_preset( params, preset, err, err_size ) != 0 )
	{
		return -1;
	}
	for ( int k = 0; k < set_count; ++k )
	{
		if ( sere_params_set( params, sets[k], err, err_size ) != 0 )
		{
			return -1;
		}
	}
	return 0;
}

void sere_params_print_json( const sere_sim_params* params, FILE* f, const char* indent )
{
	size_t count = sizeof( keys ) / sizeof( keys[0] );
	for ( size_t i = 0; i < count; ++i )
	{
		double value;
		memcpy( &value, (const char*) params + keys[i].offset, sizeof( double ) );
		const char* end = i + 1 < count ? ",\n" : "\n";
		/* JSON has no infinity: the ground's −inf ("no plane") is written as null */
		if ( isfinite( value ) )
		{
			fprintf( f, "%s\"%s\": %.17g%s", indent, keys[i].name, value, end );
		}
		else
		{
			fprintf( f, "%s\"%s\": null%s", indent, keys[i].name, end );
		}
	}
}

void sere_params_describe( FILE* f )
{
	sere_sim_params defaults = sere_sim_params_default();
	for ( size_t i = 0; i < sizeof( keys ) / sizeof( keys[0] ); ++i )
	{
		double value;
		memcpy( &value, (const char*) &defaults + keys[i].offset, sizeof( double ) );
		fprintf( f, "  %-20s %s (default %g, range [%g, %g])\n", keys[i].name, keys[i].help, value, keys[i].lo,
				 keys[i].hi );
	}
}
