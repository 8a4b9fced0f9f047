/* leafgen — the shared part of the leaf generator (see leafgen.c): 2D vectors, paths, lobes
 * and blades, the leaf under construction, and the outline and vein steps the species use. */
#pragma once

#include "read/leaffile.h"

#include <math.h>

#define PI 3.14159265358979323846

typedef struct vec2
{
	double x, y;
} vec2;

static inline vec2 v2( double x, double y )
{
	return ( vec2 ){ x, y };
}

static inline vec2 add( vec2 a, vec2 b )
{
	return v2( a.x + b.x, a.y + b.y );
}

static inline vec2 sub( vec2 a, vec2 b )
{
	return v2( a.x - b.x, a.y - b.y );
}

static inline vec2 mul( vec2 a, double s )
{
	return v2( a.x * s, a.y * s );
}

static inline double dot( vec2 a, vec2 b )
{
	return a.x * b.x + a.y * b.y;
}

static inline double cross( vec2 a, vec2 b )
{
	return a.x * b.y - a.y * b.x;
}

static inline double length( vec2 a )
{
	return sqrt( a.x * a.x + a.y * a.y );
}

/* A heading in degrees from +y, counter-clockwise: 0 points up, 90 left, -90 right. */
static inline vec2 heading( double degrees )
{
	double a = degrees * PI / 180.0;
	return v2( -sin( a ), cos( a ) );
}

static inline double smoothstep( double lo, double hi, double x )
{
	double t = fmin( 1.0, fmax( 0.0, ( x - lo ) / ( hi - lo ) ) );
	return t * t * ( 3.0 - 2.0 * t );
}

/* Polynomial smooth minimum: equals min(a, b) once they differ by more than k. */
static inline double smooth_min( double a, double b, double k )
{
	double h = fmax( k - fabs( a - b ), 0.0 ) / k;
	return fmin( a, b ) - h * h * k * 0.25;
}

static inline double segment_distance( vec2 p, vec2 a, vec2 b )
{
	vec2 e = sub( b, a );
	double l2 = dot( e, e );
	double t = l2 > 0.0 ? fmin( 1.0, fmax( 0.0, dot( sub( p, a ), e ) / l2 ) ) : 0.0;
	return length( sub( add( a, mul( e, t ) ), p ) );
}

typedef struct path
{
	vec2* p;
	int count, capacity;
} path;

/* ---- blade fields ---------------------------------------------------------------------- */

#define LOBE_STEPS 40
#define MAX_LOBES  32

/* A lobe: a tube around a gently curved axis whose half-width rises from neck to width at
 * peak (0..1 along the axis) and then narrows to tip; taper > 1 draws the narrowing out into an
 * acuminate point, < 1 keeps the lobe broad to its end. */
typedef struct lobe
{
	vec2 start;
	double angle;  /* heading at the start, degrees */
	double bend;   /* degrees the axis turns over its length (positive: counter-clockwise) */
	double length; /* along the axis */
	double neck, width, peak, taper, tip;
	double swell; /* > 1 keeps the lobe narrow longer after its neck (a deep sinus) */
	double teeth; /* serration weight on this lobe, 0..1 */
	int parent;	  /* lobe whose axis it starts on (a lobule), or -1 */
	double at;	  /* a lobule's start: this fraction along its parent's axis */
	vec2 axis[LOBE_STEPS + 1];
	double radius[LOBE_STEPS + 1];
	vec2 centre; /* a circle holding the whole lobe, to skip it when far away */
	double reach;
} lobe;

/* A blade: lobes around a junction (the top of the petiole), an optional disc there, an
 * optional V-shaped sinus cut below it (a cordate base) and an optional flat cut (a truncate
 * base, as where a grass blade leaves its sheath). */
typedef struct blade
{
	lobe lobes[MAX_LOBES];
	int lobe_count;
	vec2 junction;
	double disc;	   /* radius of the central disc, 0 for none */
	double blend;	   /* width of the smooth union between lobes */
	double sinus;	   /* depth below the junction of the cordate sinus's apex, 0 for none */
	double sinus_half; /* its half-angle, degrees */
	double cut;		   /* y below which the blade is cut flat, or -INFINITY */
	double disc_teeth; /* serration weight on the disc */
	double teeth_from; /* teeth start this far (0..1) along each lobe */
} blade;

typedef double field_fn( const void* shape, vec2 p );
typedef double teeth_fn( const void* shape, vec2 p, double* tipward );

#define MAX_VEINS 256

typedef struct vein
{
	int order, parent;
	path points;
} vein;

typedef struct leaf
{
	const char* name;
	path outline; /* leaf coordinates, counter-clockwise, outline.p[0] is the base */
	vein veins[MAX_VEINS];
	int vein_count;
	double margin; /* a vein stays this far inside the outline once it has left the base */
	double gap;	   /* and this far from other veins once it has left its start, */
	double start;  /* which is the first `start` of its length */
	vec2 origin;   /* design coordinates of the base */
	double scale;  /* design -> leaf units */
} leaf;

void die( const char* what, const char* name );
void push( path* path, vec2 p );
double lobe_width( const lobe* l, double t );
void lobe_build( lobe* l );
double blade_field( const void* shape, vec2 p );
double blade_teeth( const void* shape, vec2 p, double* tipward );
double polygon_area( const path* poly );
double polygon_perimeter( const path* poly );
path resample( const path* poly, double start, int count );
vec2 to_leaf( const leaf* l, vec2 p );
vec2 quantized( vec2 p );
void make_outline( leaf* l, field_fn* field, const void* shape, vec2 junction, int count );
void serrate( leaf* l, teeth_fn* teeth, const void* shape, double wavelength, double depth, double duty, double fine );

int add_vein( leaf* l, int order, int parent, const path* proposed, double shortest );
path line( vec2 a, vec2 b, double step );
path grow( const leaf* l, vec2 start, double angle, double final, double reach, double step );
void secondaries( leaf* l, int parent, int order, int count, double lo, double hi, double angle, double final,
				  double reach, int sides );
void write_leaf( leaf* l, const char* folder, int table_n, int table_b );
void add_lobe( blade* b, lobe lobe );
lobe palm( const blade* b, double angle, double length, double neck, double width, double peak, double taper,
		   double tip, double bend, double swell );
int primaries( leaf* l, const blade* b, int* primary, double step );
leaf new_leaf( const char* name, double margin, double gap );
void add_palm_pair( blade* b, double angle, double length, double neck, double width, double peak, double taper,
					double tip, double bend, double swell );
void lobe_veins( leaf* l, const blade* b, int count, int count_basal, double lo, double hi, double angle, double final,
				 double reach );
