/* leafgen — writes the shipped leaves, data/leaves/NAME.leaf: the species of the papers' figures
 * (seed 000 Fig. 17, seed 003's cucumber and watermelon) as outline, base and veins.
 *
 * Build and run from the repository root (no Make needed); the argument is the output folder:
 *   gcc -std=c17 -O2 -Wall -Wextra -Wpedantic -Werror -Ikernels -Iharness data/tools/leafgen.c \
 *       harness/read/leaffile.c harness/common/io.c kernels/mesh/shape.c -lm -o /tmp/leafgen && /tmp/leafgen
 * data/leaves
 *
 * Deterministic: no random numbers, so the committed files are reproduced byte for byte.
 *
 * How a leaf is made. A blade is the zero level set of a distance-like field: every lobe is a
 * tapered tube around an axis (a chain of cone segments whose radius follows the lobe's width
 * profile), joined to the others and to an optional central disc by a smooth minimum, which
 * rounds the sinuses between lobes the way real ones are rounded. The level set is traced with
 * marching squares, resampled to equal arc lengths starting at the base (where a ray straight
 * down from the petiole junction leaves the blade), scaled so the leaf's larger side is one
 * unit, and optionally serrated: teeth are offsets along the outward normal whose saw profile
 * leans towards the tip of the lobe they sit on. Veins follow the lobe axes (primaries), grow
 * off them towards the margin (secondaries), and are clipped where they would come within a
 * margin of the outline or within a gap of another vein, so every vein ends strictly inside,
 * no two veins cross, and a branch starts exactly on a point of its parent.
 *
 * The three Table 1 leaves are tuned so that perimeter^2 / area suits their point counts: a
 * sampler that puts B of N points on the outline at the interior spacing s needs
 * P^2/A = 4 B^2 / (sqrt(3) (2N - B - 2)) (kernels/mesh/sample.c); the program prints both. */
#include "read/leaffile.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define PI 3.14159265358979323846

typedef struct vec2
{
	double x, y;
} vec2;

static vec2 v2( double x, double y )
{
	return ( vec2 ){ x, y };
}

static vec2 add( vec2 a, vec2 b )
{
	return v2( a.x + b.x, a.y + b.y );
}

static vec2 sub( vec2 a, vec2 b )
{
	return v2( a.x - b.x, a.y - b.y );
}

static vec2 mul( vec2 a, double s )
{
	return v2( a.x * s, a.y * s );
}

static double dot( vec2 a, vec2 b )
{
	return a.x * b.x + a.y * b.y;
}

static double cross( vec2 a, vec2 b )
{
	return a.x * b.y - a.y * b.x;
}

static double length( vec2 a )
{
	return sqrt( a.x * a.x + a.y * a.y );
}

/* A heading in degrees from +y, counter-clockwise: 0 points up, 90 left, -90 right. */
static vec2 heading( double degrees )
{
	double a = degrees * PI / 180.0;
	return v2( -sin( a ), cos( a ) );
}

static double smoothstep( double lo, double hi, double x )
{
	double t = fmin( 1.0, fmax( 0.0, ( x - lo ) / ( hi - lo ) ) );
	return t * t * ( 3.0 - 2.0 * t );
}

/* Polynomial smooth minimum: equals min(a, b) once they differ by more than k. */
static double smooth_min( double a, double b, double k )
{
	double h = fmax( k - fabs( a - b ), 0.0 ) / k;
	return fmin( a, b ) - h * h * k * 0.25;
}

static double segment_distance( vec2 p, vec2 a, vec2 b )
{
	vec2 e = sub( b, a );
	double l2 = dot( e, e );
	double t = l2 > 0.0 ? fmin( 1.0, fmax( 0.0, dot( sub( p, a ), e ) / l2 ) ) : 0.0;
	return length( sub( add( a, mul( e, t ) ), p ) );
}

static void die( const char* what, const char* name )
{
	fprintf( stderr, "leafgen: %s: %s\n", name, what );
	exit( 1 );
}

typedef struct path
{
	vec2* p;
	int count, capacity;
} path;

static void push( path* path, vec2 p )
{
	if ( path->count == path->capacity )
	{
		path->capacity = path->capacity > 0 ? 2 * path->capacity : 64;
		path->p = realloc( path->p, sizeof( vec2 ) * (size_t) path->capacity );
		if ( path->p == NULL )
		{
			die( "out of memory", "path" );
		}
	}
	path->p[path->count++] = p;
}

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

static double lobe_width( const lobe* l, double t )
{
	if ( t <= l->peak )
	{
		double rise = sin( 0.5 * PI * t / l->peak );
		return l->neck + ( l->width - l->neck ) * pow( rise, l->swell );
	}
	double u = ( t - l->peak ) / ( 1.0 - l->peak );
	return l->tip + ( l->width - l->tip ) * pow( cos( 0.5 * PI * u ), l->taper );
}

static void lobe_build( lobe* l )
{
	vec2 p = l->start;
	double step = l->length / LOBE_STEPS;
	for ( int k = 0; k <= LOBE_STEPS; ++k )
	{
		double t = (double) k / LOBE_STEPS;
		l->axis[k] = p;
		l->radius[k] = lobe_width( l, t );
		p = add( p, mul( heading( l->angle + l->bend * ( t + 0.5 / LOBE_STEPS ) ), step ) );
	}
	l->centre = mul( add( l->axis[0], l->axis[LOBE_STEPS] ), 0.5 );
	l->reach = 0.0;
	for ( int k = 0; k <= LOBE_STEPS; ++k )
	{
		l->reach = fmax( l->reach, length( sub( l->axis[k], l->centre ) ) + l->radius[k] );
	}
}

/* Distance to the union of a disc of radius ra at a and one of radius rb at b and the cone
 * tangent to both (a round-ended tapered segment). */
static double cone_distance( vec2 p, vec2 a, vec2 b, double ra, double rb, double* along )
{
	vec2 e = sub( b, a );
	double h = length( e );
	vec2 u = mul( e, 1.0 / h );
	vec2 q = sub( p, a );
	double y = dot( q, u ), x = fabs( cross( u, q ) );
	*along = fmin( 1.0, fmax( 0.0, y / h ) );
	double s = ( ra - rb ) / h;
	if ( fabs( s ) >= 1.0 )
	{
		return fmin( length( q ) - ra, length( sub( p, b ) ) - rb );
	}
	double c = sqrt( 1.0 - s * s );
	double k = -s * x + c * y;
	if ( k < 0.0 )
	{
		return length( q ) - ra;
	}
	if ( k > c * h )
	{
		return length( sub( p, b ) ) - rb;
	}
	return c * x + s * y - ra;
}

/* Signed distance to a lobe and where along its axis (0..1) the nearest part is. */
static double lobe_distance( const lobe* l, vec2 p, double* t )
{
	double best = INFINITY;
	*t = 0.0;
	const double half_step = 0.5 * l->length / LOBE_STEPS;
	for ( int k = 0; k < LOBE_STEPS; ++k )
	{
		/* The segment lies in a circle about its middle: skip it if that is farther than best. */
		vec2 q = sub( p, mul( add( l->axis[k], l->axis[k + 1] ), 0.5 ) );
		double bound = best + half_step + fmax( l->radius[k], l->radius[k + 1] );
		if ( bound < 0.0 || dot( q, q ) > bound * bound )
		{
			continue;
		}
		double along;
		double d = cone_distance( p, l->axis[k], l->axis[k + 1], l->radius[k], l->radius[k + 1], &along );
		if ( d < best )
		{
			best = d;
			*t = ( k + along ) / LOBE_STEPS;
		}
	}
	return best;
}

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

static double blade_field( const void* shape, vec2 p )
{
	const blade* b = shape;
	double f = b->disc > 0.0 ? length( sub( p, b->junction ) ) - b->disc : INFINITY;
	for ( int i = 0; i < b->lobe_count; ++i )
	{
		/* A lobe farther than f + blend does not change the smooth minimum. */
		const lobe* lobe = b->lobes + i;
		if ( length( sub( p, lobe->centre ) ) - lobe->reach > f + b->blend )
		{
			continue;
		}
		double t;
		double d = lobe_distance( lobe, p, &t );
		f = isfinite( f ) ? smooth_min( f, d, b->blend ) : d;
	}
	if ( b->sinus > 0.0 )
	{
		/* A wedge opening downwards with its apex below the junction, subtracted smoothly. */
		double a = b->sinus_half * PI / 180.0;
		vec2 q = sub( p, v2( b->junction.x, b->junction.y - b->sinus ) );
		double wedge = fabs( q.x ) * cos( a ) + q.y * sin( a );
		f = -smooth_min( -f, wedge, 0.5 * b->blend );
	}
	return fmax( f, b->cut - p.y );
}

/* Serration weight at p and a coordinate that grows towards the tip of the lobe p belongs to. */
static double blade_teeth( const void* shape, vec2 p, double* tipward )
{
	const blade* b = shape;
	double best = b->disc > 0.0 ? length( sub( p, b->junction ) ) - b->disc : INFINITY, weight = b->disc_teeth;
	*tipward = 0.0;
	for ( int i = 0; i < b->lobe_count; ++i )
	{
		double t;
		double d = lobe_distance( b->lobes + i, p, &t );
		if ( d < best )
		{
			best = d;
			*tipward = t;
			weight = b->lobes[i].teeth * smoothstep( b->teeth_from, b->teeth_from + 0.15, t );
		}
	}
	return weight;
}

typedef double field_fn( const void* shape, vec2 p );
typedef double teeth_fn( const void* shape, vec2 p, double* tipward );

/* ---- tracing the outline ---------------------------------------------------------------- */

static double polygon_area( const path* poly )
{
	double twice = 0.0;
	for ( int i = 0, j = poly->count - 1; i < poly->count; j = i++ )
	{
		twice += cross( poly->p[j], poly->p[i] );
	}
	return 0.5 * twice;
}

static double polygon_perimeter( const path* poly )
{
	double total = 0.0;
	for ( int i = 0, j = poly->count - 1; i < poly->count; j = i++ )
	{
		total += length( sub( poly->p[i], poly->p[j] ) );
	}
	return total;
}

/* Marching squares on a grid over [lo, hi] with the given cell; returns the largest closed
 * contour, counter-clockwise (segments are oriented with the inside, f < 0, on their left, so
 * outer boundaries come out counter-clockwise and holes clockwise). */
static path trace( field_fn* field, const void* shape, vec2 lo, vec2 hi, double cell )
{
	const int nx = (int) ceil( ( hi.x - lo.x ) / cell ) + 1, ny = (int) ceil( ( hi.y - lo.y ) / cell ) + 1;
	const size_t nodes = (size_t) nx * (size_t) ny;
	double* f = malloc( sizeof( double ) * nodes );
	int* next = malloc( sizeof( int ) * 2 * nodes );
	char* seen = calloc( 2 * nodes, 1 );
	if ( f == NULL || next == NULL || seen == NULL )
	{
		die( "out of memory", "trace" );
	}
	for ( int j = 0; j < ny; ++j )
	{
		for ( int i = 0; i < nx; ++i )
		{
			f[(size_t) j * nx + i] = field( shape, v2( lo.x + i * cell, lo.y + j * cell ) );
		}
	}
	for ( size_t k = 0; k < 2 * nodes; ++k )
	{
		next[k] = -1;
	}
	/* Crossing ids: horizontal edge (i, j)-(i+1, j) is j*nx + i, vertical (i, j)-(i, j+1) is
	 * nodes + j*nx + i. */
	for ( int j = 0; j + 1 < ny; ++j )
	{
		for ( int i = 0; i + 1 < nx; ++i )
		{
			size_t c[4] = { (size_t) j * nx + i, (size_t) j * nx + i + 1, (size_t) ( j + 1 ) * nx + i + 1,
							(size_t) ( j + 1 ) * nx + i };
			int edge[4] = { (int) c[0], (int) ( nodes + c[1] ), (int) c[3], (int) ( nodes + c[0] ) };
			int order[4], kinds[4], count = 0;
			for ( int k = 0; k < 4; ++k )
			{
				int in_a = f[c[k]] < 0.0, in_b = f[c[( k + 1 ) % 4]] < 0.0;
				if ( in_a != in_b )
				{
					order[count] = edge[k];
					kinds[count++] = in_a; /* 1: leaving the inside (a segment starts here) */
				}
			}
			if ( count == 2 )
			{
				int s = kinds[0] ? 0 : 1;
				next[order[s]] = order[1 - s];
			}
			else if ( count == 4 )
			{
				/* A saddle: the centre decides whether the inside corners are joined. */
				int joined = 0.25 * ( f[c[0]] + f[c[1]] + f[c[2]] + f[c[3]] ) < 0.0;
				for ( int s = 0; s < 4; ++s )
				{
					if ( kinds[s] )
					{
						next[order[s]] = order[joined ? ( s + 1 ) % 4 : ( s + 3 ) % 4];
					}
				}
			}
		}
	}
	path best = { 0 };
	double best_area = 0.0;
	for ( size_t k = 0; k < 2 * nodes; ++k )
	{
		if ( next[k] < 0 || seen[k] )
		{
			continue;
		}
		path loop = { 0 };
		for ( int id = (int) k; !seen[id]; id = next[id] )
		{
			seen[id] = 1;
			size_t a = (size_t) id < nodes ? (size_t) id : (size_t) id - nodes;
			size_t b = (size_t) id < nodes ? a + 1 : a + (size_t) nx;
			double t = f[a] / ( f[a] - f[b] );
			vec2 pa = v2( lo.x + (double) ( a % nx ) * cell, lo.y + (double) ( a / nx ) * cell );
			vec2 pb = v2( lo.x + (double) ( b % nx ) * cell, lo.y + (double) ( b / nx ) * cell );
			push( &loop, add( pa, mul( sub( pb, pa ), t ) ) );
			if ( next[id] < 0 )
			{
				die( "open contour (the blade touches the grid's border)", "trace" );
			}
		}
		double area = polygon_area( &loop );
		if ( area > best_area )
		{
			free( best.p );
			best = loop;
			best_area = area;
		}
		else
		{
			free( loop.p );
		}
	}
	free( f );
	free( next );
	free( seen );
	return best;
}

/* count points at equal arc length along the closed polygon, the first at arc position start. */
static path resample( const path* poly, double start, int count )
{
	double total = polygon_perimeter( poly );
	path out = { 0 };
	int seg = 0;
	double seg_start = 0.0;
	for ( int k = 0; k < count; ++k )
	{
		double s = fmod( start + total * k / count, total );
		if ( s < seg_start )
		{
			seg = 0;
			seg_start = 0.0;
		}
		for ( ;; )
		{
			double l = length( sub( poly->p[( seg + 1 ) % poly->count], poly->p[seg] ) );
			if ( s <= seg_start + l || seg == poly->count - 1 )
			{
				double t = l > 0.0 ? fmin( 1.0, ( s - seg_start ) / l ) : 0.0;
				vec2 a = poly->p[seg], b = poly->p[( seg + 1 ) % poly->count];
				push( &out, add( a, mul( sub( b, a ), t ) ) );
				break;
			}
			seg_start += l;
			seg += 1;
		}
	}
	return out;
}

/* Arc position along the closed polygon of the point nearest p. */
static double arc_position( const path* poly, vec2 p )
{
	double best = INFINITY, at = 0.0, s = 0.0;
	for ( int i = 0; i < poly->count; ++i )
	{
		vec2 a = poly->p[i], b = poly->p[( i + 1 ) % poly->count];
		vec2 e = sub( b, a );
		double l = length( e );
		double t = l > 0.0 ? fmin( 1.0, fmax( 0.0, dot( sub( p, a ), e ) / ( l * l ) ) ) : 0.0;
		double d = length( sub( add( a, mul( e, t ) ), p ) );
		if ( d < best )
		{
			best = d;
			at = s + t * l;
		}
		s += l;
	}
	return at;
}

/* ---- a leaf under construction ---------------------------------------------------------- */

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

static vec2 to_leaf( const leaf* l, vec2 p )
{
	return mul( sub( p, l->origin ), l->scale );
}

/* Coordinates are kept to 6 decimals, so files stay short; the outline is rounded as soon as it
 * is final and every vein point as it is added, so the checks see exactly what is written. */
static double quantize( double x )
{
	/* + 0.0 turns a -0 into 0, which would otherwise be written as "-0". */
	return round( x * 1e6 ) / 1e6 + 0.0;
}

static vec2 quantized( vec2 p )
{
	return v2( quantize( p.x ), quantize( p.y ) );
}

/* Traces the blade, starts the outline at the base (straight below the junction), scales the
 * leaf so its larger side is one unit with the base at the origin, and resamples it to count
 * points. */
static void make_outline( leaf* l, field_fn* field, const void* shape, vec2 junction, int count )
{
	/* The design's extent, from a coarse scan. */
	double x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY, span = 4.0, coarse = span / 200.0;
	for ( int j = 0; j <= 400; ++j )
	{
		for ( int i = 0; i <= 400; ++i )
		{
			vec2 p = v2( junction.x - span + i * coarse, junction.y - span + j * coarse );
			if ( field( shape, p ) < 0.0 )
			{
				x0 = fmin( x0, p.x ), x1 = fmax( x1, p.x ), y0 = fmin( y0, p.y ), y1 = fmax( y1, p.y );
			}
		}
	}
	if ( !isfinite( x0 ) )
	{
		die( "empty blade", l->name );
	}
	double size = fmax( x1 - x0, y1 - y0 ), cell = size / 1000.0;
	path contour =
		trace( field, shape, v2( x0 - 0.05 * size, y0 - 0.05 * size ), v2( x1 + 0.05 * size, y1 + 0.05 * size ), cell );

	/* The base: where a ray straight down from the junction leaves the blade. */
	double lo = 0.0, hi = 0.0;
	while ( field( shape, v2( junction.x, junction.y - hi ) ) < 0.0 )
	{
		lo = hi;
		hi += 0.25 * cell;
	}
	for ( int k = 0; k < 60; ++k )
	{
		double mid = 0.5 * ( lo + hi );
		if ( field( shape, v2( junction.x, junction.y - mid ) ) < 0.0 )
		{
			lo = mid;
		}
		else
		{
			hi = mid;
		}
	}
	path raw = resample( &contour, arc_position( &contour, v2( junction.x, junction.y - lo ) ), count );
	free( contour.p );
	double bx0 = INFINITY, bx1 = -INFINITY, by0 = INFINITY, by1 = -INFINITY;
	for ( int i = 0; i < raw.count; ++i )
	{
		bx0 = fmin( bx0, raw.p[i].x ), bx1 = fmax( bx1, raw.p[i].x );
		by0 = fmin( by0, raw.p[i].y ), by1 = fmax( by1, raw.p[i].y );
	}
	l->origin = raw.p[0];
	l->scale = 1.0 / fmax( bx1 - bx0, by1 - by0 );
	l->outline.count = 0;
	for ( int i = 0; i < raw.count; ++i )
	{
		push( &l->outline, quantized( to_leaf( l, raw.p[i] ) ) );
	}
	free( raw.p );
}

/* Box filter of a periodic sequence over 2 half + 1 samples. */
static void smooth( double* values, int n, int half )
{
	double* copy = malloc( sizeof( double ) * (size_t) n );
	if ( copy == NULL )
	{
		die( "out of memory", "smooth" );
	}
	memcpy( copy, values, sizeof( double ) * (size_t) n );
	for ( int i = 0; i < n; ++i )
	{
		double sum = 0.0;
		for ( int k = -half; k <= half; ++k )
		{
			sum += copy[( ( i + k ) % n + n ) % n];
		}
		values[i] = sum / ( 2 * half + 1 );
	}
	free( copy );
}

/* Teeth along the outline, one per wavelength (leaf units): a triangle `depth` high taking the
 * fraction `duty` of its period (1: saw teeth edge to edge; less: separate teeth with entire
 * margin between them); fine > 0 adds a second, smaller tooth on each (doubly serrate). The
 * teeth lean towards the tip of their lobe (the coordinate teeth() reports grows that way) and
 * fade out at lobe tips, where the outline is concave and tight, and where it passes close to
 * another stretch of itself (a narrow sinus), since an offset there would fold the outline
 * over itself. Weights and lean are averaged over a tooth so that neither jumps where the
 * nearest lobe changes. */
static void serrate( leaf* l, teeth_fn* teeth, const void* shape, double wavelength, double depth, double duty,
					 double fine )
{
	const int n = l->outline.count;
	vec2* p = l->outline.p;
	vec2* moved = malloc( sizeof( vec2 ) * (size_t) n );
	double* weight = malloc( sizeof( double ) * (size_t) n );
	double* tip = malloc( sizeof( double ) * (size_t) n );
	double* lean = malloc( sizeof( double ) * (size_t) n );
	double* bend = malloc( sizeof( double ) * (size_t) n );
	double* room = malloc( sizeof( double ) * (size_t) n );
	if ( moved == NULL || weight == NULL || tip == NULL || lean == NULL || bend == NULL || room == NULL )
	{
		die( "out of memory", l->name );
	}
	const double ds = polygon_perimeter( &l->outline ) / n, height = depth + fine;
	const int half = (int) fmax( 1.0, 0.5 * wavelength / ds );
	for ( int i = 0; i < n; ++i )
	{
		/* teeth() works in design coordinates. */
		vec2 design = add( mul( p[i], 1.0 / l->scale ), l->origin );
		weight[i] = teeth( shape, design, tip + i );
		/* The base stays where it is: no teeth within a tenth of the leaf of it. */
		weight[i] *= smoothstep( 0.06, 0.12, length( p[i] ) );
		vec2 a = sub( p[i], p[( i + n - 1 ) % n] ), b = sub( p[( i + 1 ) % n], p[i] );
		bend[i] = atan2( cross( a, b ), dot( a, b ) ) / ds; /* curvature, > 0 convex */
		/* Room: the distance to the nearest part of the outline that is much farther along the
		 * outline than across (the other side of a sinus). */
		double clearance = INFINITY;
		for ( int j = 0; j < n; ++j )
		{
			int apart = abs( i - j ) < n - abs( i - j ) ? abs( i - j ) : n - abs( i - j );
			double across = length( sub( p[i], p[j] ) );
			if ( apart * ds > 2.0 * across + 2.0 * ds )
			{
				clearance = fmin( clearance, across );
			}
		}
		room[i] = 0.25 * clearance / height;
	}
	for ( int i = 0; i < n; ++i )
	{
		/* +1 walking towards a tip, -1 away; 0 where the nearest lobe changes (t jumps). */
		double dt = tip[( i + 1 ) % n] - tip[( i + n - 1 ) % n];
		lean[i] = fabs( dt ) > 0.05 ? 0.0 : dt > 0.0 ? 1.0 : dt < 0.0 ? -1.0 : 0.0;
	}
	smooth( weight, n, half );
	smooth( lean, n, half );
	/* The tightest concave bend within a tooth's reach limits its teeth. */
	smooth( bend, n, 2 );
	for ( int i = 0; i < n; ++i )
	{
		double tightest = 0.0;
		for ( int k = -half; k <= half; ++k )
		{
			tightest = fmin( tightest, bend[( ( i + k ) % n + n ) % n] );
		}
		room[i] = fmin( room[i], tightest < 0.0 ? 0.35 / ( -tightest * height ) : INFINITY );
	}
	double arc = 0.0;
	for ( int i = 0; i < n; ++i )
	{
		double w = fmin( weight[i], room[i] );
		w *= 1.0 - smoothstep( 0.88, 0.97, tip[i] );
		/* Apex late in the tooth when walking towards the tip: the long flank faces the base. */
		double apex = 0.5 + 0.3 * lean[i];
		double u = ( arc / wavelength - floor( arc / wavelength ) - ( 1.0 - duty ) ) / duty;
		double saw = u < 0.0 ? 0.0 : u < apex ? u / apex : ( 1.0 - u ) / ( 1.0 - apex );
		double v = u < 0.0 ? 0.0 : 3.0 * u - floor( 3.0 * u );
		double small = v < apex ? v / apex : ( 1.0 - v ) / ( 1.0 - apex );
		double offset = w * ( depth * saw + fine * small * saw );
		vec2 tangent = sub( p[( i + 1 ) % n], p[( i + n - 1 ) % n] );
		vec2 normal = mul( v2( tangent.y, -tangent.x ), 1.0 / length( tangent ) );
		moved[i] = quantized( add( p[i], mul( normal, offset ) ) );
		arc += length( sub( p[( i + 1 ) % n], p[i] ) );
	}
	memcpy( p, moved, sizeof( vec2 ) * (size_t) n );
	free( moved );
	free( weight );
	free( tip );
	free( lean );
	free( bend );
	free( room );
}

static int inside( const leaf* l, vec2 p )
{
	int in = 0;
	const vec2* q = l->outline.p;
	for ( int i = 0, j = l->outline.count - 1; i < l->outline.count; j = i++ )
	{
		if ( ( q[i].y > p.y ) != ( q[j].y > p.y ) &&
			 p.x < q[j].x + ( p.y - q[j].y ) * ( q[i].x - q[j].x ) / ( q[i].y - q[j].y ) )
		{
			in = !in;
		}
	}
	return in;
}

static double outline_distance( const leaf* l, vec2 p )
{
	double best = INFINITY;
	for ( int i = 0, j = l->outline.count - 1; i < l->outline.count; j = i++ )
	{
		best = fmin( best, segment_distance( p, l->outline.p[j], l->outline.p[i] ) );
	}
	return best;
}

static int segments_cross( vec2 a, vec2 b, vec2 c, vec2 d )
{
	double o1 = cross( sub( b, a ), sub( c, a ) ), o2 = cross( sub( b, a ), sub( d, a ) );
	double o3 = cross( sub( d, c ), sub( a, c ) ), o4 = cross( sub( d, c ), sub( b, c ) );
	return ( ( o1 > 0 ) != ( o2 > 0 ) ) && ( ( o3 > 0 ) != ( o4 > 0 ) );
}

/* Adds the longest usable prefix of a proposed vein (its first point a point of the parent, or
 * the base): every later point inside the outline, at least margin inside once the vein has
 * got that far from it, at least gap from every other vein once it has run `start` from its
 * first point, and no segment crossing a vein. Returns the new vein's index, or -1 if too
 * little is left. */
static int add_vein( leaf* l, int order, int parent, const path* proposed, double shortest )
{
	if ( l->vein_count == MAX_VEINS )
	{
		die( "too many veins", l->name );
	}
	vein* v = l->veins + l->vein_count;
	*v = ( vein ){ order, parent, { 0 } };
	vec2 first = quantized( proposed->p[0] );
	push( &v->points, first );
	int clear = 0;
	double run = 0.0;
	for ( int k = 1; k < proposed->count; ++k )
	{
		vec2 p = quantized( proposed->p[k] ), previous = v->points.p[v->points.count - 1];
		if ( p.x == previous.x && p.y == previous.y )
		{
			continue;
		}
		if ( !inside( l, p ) )
		{
			break;
		}
		double d = outline_distance( l, p );
		if ( clear && d < l->margin )
		{
			break;
		}
		run += length( sub( p, previous ) );
		int ok = 1;
		for ( int w = 0; w < l->vein_count && ok; ++w )
		{
			const path* other = &l->veins[w].points;
			for ( int j = 0; j + 1 < other->count && ok; ++j )
			{
				vec2 a = other->p[j], b = other->p[j + 1];
				int touches_start = ( a.x == first.x && a.y == first.y ) || ( b.x == first.x && b.y == first.y );
				if ( segments_cross( previous, p, a, b ) && !( v->points.count == 1 && touches_start ) )
				{
					ok = 0;
				}
				else if ( run > l->start && segment_distance( p, a, b ) < l->gap )
				{
					ok = 0;
				}
			}
		}
		if ( !ok )
		{
			break;
		}
		push( &v->points, p );
		clear |= d >= l->margin;
	}
	double total = 0.0;
	for ( int k = 1; k < v->points.count; ++k )
	{
		total += length( sub( v->points.p[k], v->points.p[k - 1] ) );
	}
	/* The end must keep the margin too (a vein from the base that never got clear of it fails). */
	if ( v->points.count < 2 || total < shortest || !clear ||
		 outline_distance( l, v->points.p[v->points.count - 1] ) < l->margin )
	{
		free( v->points.p );
		return -1;
	}
	return l->vein_count++;
}

/* A straight proposed vein from a to b in steps of about step. */
static path line( vec2 a, vec2 b, double step )
{
	path out = { 0 };
	int pieces = (int) fmax( 1.0, ceil( length( sub( b, a ) ) / step ) );
	for ( int k = 0; k <= pieces; ++k )
	{
		push( &out, add( a, mul( sub( b, a ), (double) k / pieces ) ) );
	}
	return out;
}

/* A proposed vein from first along a lobe's axis (leaf coordinates), refined to about step. */
static path along_axis( const leaf* l, const lobe* lobe, double step, vec2 first )
{
	path out = { 0 };
	push( &out, first );
	for ( int k = 0; k < LOBE_STEPS; ++k )
	{
		vec2 a = to_leaf( l, lobe->axis[k] ), b = to_leaf( l, lobe->axis[k + 1] );
		int pieces = (int) fmax( 1.0, ceil( length( sub( b, a ) ) / step ) );
		for ( int q = 1; q <= pieces; ++q )
		{
			push( &out, add( a, mul( sub( b, a ), (double) q / pieces ) ) );
		}
	}
	return out;
}

/* A vein grown from start with heading `angle` that turns towards heading `final` as it nears
 * the margin (in proportion to how much of its starting clearance is used up), at most
 * `reach` long. */
static path grow( const leaf* l, vec2 start, double angle, double final, double reach, double step )
{
	path out = { 0 };
	push( &out, start );
	double clearance = fmax( outline_distance( l, start ), 1e-9 );
	vec2 p = start;
	double turn = remainder( final - angle, 360.0 );
	for ( double run = 0.0; run < reach; run += step )
	{
		double used = 1.0 - fmin( 1.0, outline_distance( l, p ) / clearance );
		p = add( p, mul( heading( angle + turn * used ), step ) );
		push( &out, p );
	}
	return out;
}

/* The vertex of a vein nearest a fraction (0..1) of its length. */
static int vertex_at( const path* vein, double fraction )
{
	double total = 0.0;
	for ( int k = 1; k < vein->count; ++k )
	{
		total += length( sub( vein->p[k], vein->p[k - 1] ) );
	}
	double run = 0.0;
	for ( int k = 1; k < vein->count; ++k )
	{
		run += length( sub( vein->p[k], vein->p[k - 1] ) );
		if ( run >= fraction * total )
		{
			return k;
		}
	}
	return vein->count - 1;
}

/* Heading of a vein at vertex k, degrees. */
static double vein_heading( const path* vein, int k )
{
	vec2 d = sub( vein->p[k < vein->count - 1 ? k + 1 : k], vein->p[k > 0 ? k - 1 : k] );
	return atan2( -d.x, d.y ) * 180.0 / PI;
}

/* Secondary veins off vein `parent`: count per side, evenly from fraction lo to hi of its
 * length, leaving at `angle` degrees from the parent and bending to `final` degrees from it by
 * the margin; `sides` 1 grows them only on the left, -1 only on the right, 0 on both. Grown
 * from the tip towards the base, so each one stops short of the one above it (brochidodromous
 * loops seen from afar). */
static void secondaries( leaf* l, int parent, int order, int count, double lo, double hi, double angle, double final,
						 double reach, int sides )
{
	for ( int s = count - 1; s >= 0; --s )
	{
		double fraction = count > 1 ? lo + ( hi - lo ) * s / ( count - 1 ) : lo;
		for ( int side = -1; side <= 1; side += 2 )
		{
			if ( sides != 0 && side != sides )
			{
				continue;
			}
			/* Alternate a little, as real secondaries do. */
			double shift = side > 0 ? 0.0 : 0.35 * ( hi - lo ) / fmax( 1.0, count - 1.0 );
			const path* pv = &l->veins[parent].points;
			int k = vertex_at( pv, fmin( hi, fraction + shift ) );
			if ( k <= 0 || k >= pv->count - 1 )
			{
				continue;
			}
			double h = vein_heading( pv, k );
			path proposed = grow( l, pv->p[k], h + side * angle, h + side * final, reach, 0.006 );
			add_vein( l, order, parent, &proposed, 2.0 * l->margin );
			free( proposed.p );
		}
	}
}

/* ---- output ---------------------------------------------------------------------------- */

/* perimeter^2 / area of the outline resampled at b equal arcs, as the sampler sees it. */
static double ratio_at( const leaf* l, int b )
{
	path coarse = resample( &l->outline, 0.0, b );
	double perimeter = polygon_perimeter( &coarse ), area = polygon_area( &coarse );
	free( coarse.p );
	return perimeter * perimeter / area;
}

static void write_leaf( leaf* l, const char* folder, int table_n, int table_b )
{
	int points = 0;
	for ( int v = 0; v < l->vein_count; ++v )
	{
		points += l->veins[v].points.count;
	}
	double* outline_xy = malloc( sizeof( double ) * 2 * (size_t) l->outline.count );
	double* vein_xy = malloc( sizeof( double ) * 2 * (size_t) ( points > 0 ? points : 1 ) );
	sere_vein* veins = malloc( sizeof( sere_vein ) * (size_t) ( l->vein_count > 0 ? l->vein_count : 1 ) );
	if ( outline_xy == NULL || vein_xy == NULL || veins == NULL )
	{
		die( "out of memory", l->name );
	}
	for ( int i = 0; i < l->outline.count; ++i )
	{
		outline_xy[2 * i] = l->outline.p[i].x;
		outline_xy[2 * i + 1] = l->outline.p[i].y;
	}
	int first = 0;
	for ( int v = 0; v < l->vein_count; ++v )
	{
		const vein* vn = l->veins + v;
		veins[v] = ( sere_vein ){ first, vn->points.count, vn->order, vn->parent };
		for ( int k = 0; k < vn->points.count; ++k )
		{
			vein_xy[2 * ( first + k )] = vn->points.p[k].x;
			vein_xy[2 * ( first + k ) + 1] = vn->points.p[k].y;
		}
		first += vn->points.count;
	}
	sere_leaf_shape shape = {
		.base_x = l->outline.p[0].x,
		.base_y = l->outline.p[0].y,
		.outline_count = l->outline.count,
		.outline_xy = outline_xy,
		.vein_count = l->vein_count,
		.veins = veins,
		.vein_point_count = points,
		.vein_xy = vein_xy,
	};
	sere_shape_check check;
	if ( sere_shape_validate( &shape, &check ) != SERE_OK )
	{
		const double* at = check.point < 0	? NULL
						   : check.vein < 0 ? outline_xy + 2 * check.point
											: vein_xy + 2 * check.point;
		fprintf( stderr, "leafgen: %s: %s (vein %d, point %d at %g %g)\n", l->name,
				 sere_shape_problem_text( check.problem ), check.vein, check.point, at ? at[0] : NAN,
				 at ? at[1] : NAN );
		exit( 1 );
	}
	char path[1024], err[1024];
	snprintf( path, sizeof( path ), "%s/%s.leaf", folder, l->name );
	if ( sere_leaf_file_write( path, &shape, l->name, err, sizeof( err ) ) != SERE_OK )
	{
		die( err, l->name );
	}
	double perimeter = polygon_perimeter( &l->outline ), area = polygon_area( &l->outline );
	printf( "%-10s outline %4d  veins %3d (%4d points)  P^2/A %6.1f", l->name, l->outline.count, l->vein_count, points,
			perimeter * perimeter / area );
	if ( table_n > 0 )
	{
		double ideal = 4.0 * table_b * table_b / ( sqrt( 3.0 ) * ( 2.0 * table_n - table_b - 2.0 ) );
		printf( "  at B=%d: %6.1f  (sampler's ideal for N=%d: %.1f)", table_b, ratio_at( l, table_b ), table_n, ideal );
	}
	printf( "\n" );
	free( outline_xy );
	free( vein_xy );
	free( veins );
	for ( int v = 0; v < l->vein_count; ++v )
	{
		free( l->veins[v].points.p );
	}
	free( l->outline.p );
}

/* ---- palmate and pinnate blades --------------------------------------------------------- */

static void add_lobe( blade* b, lobe lobe )
{
	if ( lobe.parent >= 0 )
	{
		lobe.start = b->lobes[lobe.parent].axis[(int) round( lobe.at * LOBE_STEPS )];
	}
	lobe_build( &lobe );
	b->lobes[b->lobe_count++] = lobe;
}

/* A lobe from the junction: heading, length, neck, width, peak, taper, tip, bend. */
static lobe palm( const blade* b, double angle, double length, double neck, double width, double peak, double taper,
				  double tip, double bend, double swell )
{
	return ( lobe ){ .start = b->junction,
					 .angle = angle,
					 .bend = bend,
					 .length = length,
					 .neck = neck,
					 .width = width,
					 .peak = peak,
					 .taper = taper,
					 .tip = tip,
					 .swell = swell,
					 .teeth = 1.0,
					 .parent = -1 };
}

/* The midvein (base -> junction -> along lobe 0) and one primary vein along every other lobe
 * that starts at the junction; lobules get a vein from the point of their parent's vein where
 * they start. primary[i] is the vein along lobe i (-1 if none fitted); returns the midvein's
 * vertex at the junction. */
static int primaries( leaf* l, const blade* b, int* primary, double step )
{
	path mid = line( v2( 0.0, 0.0 ), to_leaf( l, b->junction ), step );
	int junction = mid.count - 1;
	path axis = along_axis( l, b->lobes, step, mid.p[junction] );
	for ( int k = 1; k < axis.count; ++k )
	{
		push( &mid, axis.p[k] );
	}
	free( axis.p );
	primary[0] = add_vein( l, 1, -1, &mid, 0.0 );
	free( mid.p );
	if ( primary[0] < 0 )
	{
		die( "no midvein fits", l->name );
	}
	vec2 junction_point = l->veins[primary[0]].points.p[junction];
	for ( int i = 1; i < b->lobe_count; ++i )
	{
		const lobe* lobe = b->lobes + i;
		primary[i] = -1;
		if ( lobe->parent < 0 )
		{
			path proposed = along_axis( l, lobe, step, junction_point );
			primary[i] = add_vein( l, 2, primary[0], &proposed, 2.0 * l->margin );
			free( proposed.p );
			continue;
		}
		int pv = primary[lobe->parent];
		if ( pv < 0 )
		{
			continue;
		}
		/* Start on the parent vein's vertex nearest the lobule's start. */
		vec2 start = to_leaf( l, lobe->start );
		const path* parent = &l->veins[pv].points;
		int best = 0;
		for ( int k = 1; k < parent->count; ++k )
		{
			if ( length( sub( parent->p[k], start ) ) < length( sub( parent->p[best], start ) ) )
			{
				best = k;
			}
		}
		path proposed = along_axis( l, lobe, step, parent->p[best] );
		primary[i] = add_vein( l, l->veins[pv].order + 1, pv, &proposed, 2.0 * l->margin );
		free( proposed.p );
	}
	return junction;
}

static leaf new_leaf( const char* name, double margin, double gap )
{
	leaf l;
	memset( &l, 0, sizeof( l ) );
	l.name = name;
	l.margin = margin;
	l.gap = gap;
	l.start = 2.0 * gap;
	return l;
}

/* The lobe and its mirror image across the midrib (heading and bend negated), for palmate
 * blades symmetric about the midrib. */
static void add_palm_pair( blade* b, double angle, double length, double neck, double width, double peak, double taper,
						   double tip, double bend, double swell )
{
	for ( int side = 1; side >= -1; side -= 2 )
	{
		add_lobe( b, palm( b, side * angle, length, neck, width, peak, taper, tip, side * bend, swell ) );
	}
}

/* A primary up every lobe and third-order secondaries on each: `count` on the first three
 * lobes (the middle one and its neighbours), `count_basal` on the others. */
static void lobe_veins( leaf* l, const blade* b, int count, int count_basal, double lo, double hi, double angle,
						double final, double reach )
{
	int primary[MAX_LOBES];
	primaries( l, b, primary, 0.008 );
	for ( int i = 0; i < b->lobe_count; ++i )
	{
		if ( primary[i] >= 0 )
		{
			secondaries( l, primary[i], 3, i < 3 ? count : count_basal, lo, hi, angle, final, reach, 0 );
		}
	}
}

/* A five-lobed palmate blade (plane, cucumber): the middle lobe along the midrib and two
 * mirrored pairs from the junction, blended at a heart-shaped sinus, serrate all round, with a
 * primary and its secondaries up every lobe. */
typedef struct palmate
{
	const char* name;
	double disc, sinus_half, disc_teeth, teeth_from; /* of the blade */
	double lobes[3][9]; /* palm's arguments from the heading on: the middle lobe, then each pair */
	int outline;		/* points on the outline */
	double teeth[4];	/* serrate's wavelength, depth, duty and fine */
	int count, count_basal;
	double veins[5]; /* lobe_veins' lo, hi, angle, final and reach */
	int table_n, table_b;
} palmate;

static void palmate_leaf( const char* folder, const palmate* p )
{
	static blade b;
	b = ( blade ){ .junction = v2( 0.0, 0.0 ),
				   .disc = p->disc,
				   .blend = 0.1,
				   .sinus = 0.1,
				   .sinus_half = p->sinus_half,
				   .cut = -INFINITY,
				   .disc_teeth = p->disc_teeth,
				   .teeth_from = p->teeth_from };
	const double* m = p->lobes[0];
	add_lobe( &b, palm( &b, m[0], m[1], m[2], m[3], m[4], m[5], m[6], m[7], m[8] ) );
	for ( int k = 1; k < 3; ++k )
	{
		const double* q = p->lobes[k];
		add_palm_pair( &b, q[0], q[1], q[2], q[3], q[4], q[5], q[6], q[7], q[8] );
	}
	leaf l = new_leaf( p->name, 0.02, 0.015 );
	make_outline( &l, blade_field, &b, b.junction, p->outline );
	serrate( &l, blade_teeth, &b, p->teeth[0], p->teeth[1], p->teeth[2], p->teeth[3] );
	const double* v = p->veins;
	lobe_veins( &l, &b, p->count, p->count_basal, v[0], v[1], v[2], v[3], v[4] );
	write_leaf( &l, folder, p->table_n, p->table_b );
}

/* Japanese maple (Acer palmatum), Fig. 17 rows 1-2: seven deep, narrow, lanceolate lobes with
 * long points, doubly serrate, the basal pair small and pointing down and out; the primaries
 * radiate from the top of the petiole. */
static void maple( const char* folder )
{
	static blade b;
	b = ( blade ){ .junction = v2( 0.0, 0.0 ), .disc = 0.12, .blend = 0.03, .cut = -INFINITY, .teeth_from = 0.25 };
	const double angle[4] = { 0.0, 47.0, 95.0, 141.0 }, len[4] = { 1.0, 0.96, 0.8, 0.46 };
	const double width[4] = { 0.124, 0.119, 0.107, 0.072 };
	for ( int k = 0; k < 4; ++k )
	{
		for ( int side = 1; side >= ( k == 0 ? 1 : -1 ); side -= 2 )
		{
			add_lobe( &b,
					  palm( &b, side * angle[k], len[k], 0.03, width[k], 0.5, 1.6, 0.0, side * 6.0 * k / 3.0, 2.0 ) );
		}
	}
	leaf l = new_leaf( "maple", 0.02, 0.012 );
	make_outline( &l, blade_field, &b, b.junction, 3000 );
	serrate( &l, blade_teeth, &b, 0.042, 0.022, 1.0, 0.005 );
	lobe_veins( &l, &b, 4, 4, 0.3, 0.8, 52.0, 20.0, 0.12 );
	write_leaf( &l, folder, 4680, 841 );
}

/* London plane (Platanus x acerifolia), Fig. 17 row 3: five broad triangular lobes with
 * moderate sinuses, a few large teeth, a truncate base; three strong primaries from the base
 * and a small basal pair. */
static void plane( const char* folder )
{
	static const palmate plane = { .name = "plane",
								   .disc = 0.37,
								   .sinus_half = 62.0,
								   .disc_teeth = 0.6,
								   .teeth_from = 0.1,
								   .lobes = { { 0.0, 1.0, 0.3, 0.37, 0.12, 1.3, 0.0, 0.0, 1.0 },
											  { 54.0, 0.95, 0.3, 0.35, 0.12, 1.3, 0.0, 6.0, 1.0 },
											  { 112.0, 0.55, 0.22, 0.25, 0.12, 1.3, 0.0, 10.0, 1.0 } },
								   .outline = 2000,
								   .teeth = { 0.1, 0.022, 0.4, 0.0 },
								   .count = 5,
								   .count_basal = 3,
								   .veins = { 0.2, 0.85, 50.0, 15.0, 0.3 },
								   .table_n = 5144,
								   .table_b = 361 };
	palmate_leaf( folder, &plane );
}

/* A single-lobed blade along +y from the junction at the origin. */
static lobe simple_blade( double neck, double width, double peak, double taper, double swell )
{
	return ( lobe ){ .start = v2( 0.0, 0.0 ),
					 .angle = 0.0,
					 .length = 1.0,
					 .neck = neck,
					 .width = width,
					 .peak = peak,
					 .taper = taper,
					 .tip = 0.0,
					 .swell = swell,
					 .teeth = 1.0,
					 .parent = -1 };
}

/* Wisteria leaflet (Wisteria floribunda), Fig. 17 row 6: elliptic-ovate with a drawn-out tip,
 * rounded base, entire margin; pinnate venation, the secondaries arching up and looping short
 * of the margin. */
static void wisteria( const char* folder )
{
	static blade b;
	b = ( blade ){ .junction = v2( 0.0, 0.0 ), .blend = 0.05, .cut = -INFINITY };
	add_lobe( &b, simple_blade( 0.06, 0.19, 0.42, 1.7, 0.7 ) );
	leaf l = new_leaf( "wisteria", 0.02, 0.014 );
	make_outline( &l, blade_field, &b, b.junction, 1200 );
	int primary[MAX_LOBES];
	primaries( &l, &b, primary, 0.008 );
	secondaries( &l, primary[0], 2, 7, 0.1, 0.8, 58.0, 8.0, 0.6, 0 );
	write_leaf( &l, folder, 4344, 280 );
}

/* Shellbark hickory leaflet (Carya laciniosa), seed 003: long, widest above the middle, a long
 * point, finely and regularly serrate; many straight parallel secondaries running out to the
 * teeth. */
static void hickory( const char* folder )
{
	static blade b;
	b = ( blade ){ .junction = v2( 0.0, 0.0 ), .blend = 0.05, .cut = -INFINITY, .teeth_from = 0.12 };
	add_lobe( &b, simple_blade( 0.025, 0.155, 0.56, 1.8, 1.3 ) );
	leaf l = new_leaf( "hickory", 0.02, 0.012 );
	make_outline( &l, blade_field, &b, b.junction, 1800 );
	serrate( &l, blade_teeth, &b, 0.026, 0.007, 1.0, 0.0 );
	int primary[MAX_LOBES];
	primaries( &l, &b, primary, 0.008 );
	secondaries( &l, primary[0], 2, 12, 0.08, 0.86, 48.0, 28.0, 0.4, 0 );
	write_leaf( &l, folder, 0, 0 );
}

/* Chinese hibiscus (Hibiscus rosa-sinensis), Fig. 17 row 4: ovate with a pointed tip, a rounded
 * base and coarse teeth above it; three strong veins from the base (palmate), a short basal
 * pair, and pinnate secondaries on the upper midvein. */
static void hibiscus( const char* folder )
{
	static blade b;
	b = ( blade ){ .junction = v2( 0.0, 0.0 ), .blend = 0.05, .cut = -INFINITY, .teeth_from = 0.22 };
	add_lobe( &b, simple_blade( 0.24, 0.42, 0.26, 1.4, 0.6 ) );
	leaf l = new_leaf( "hibiscus", 0.02, 0.014 );
	make_outline( &l, blade_field, &b, b.junction, 2000 );
	serrate( &l, blade_teeth, &b, 0.055, 0.016, 1.0, 0.0 );
	int primary[MAX_LOBES];
	int junction = primaries( &l, &b, primary, 0.008 );
	vec2 at = l.veins[primary[0]].points.p[junction];
	for ( int side = 1; side >= -1; side -= 2 )
	{
		path proposed = grow( &l, at, side * 38.0, side * 14.0, 0.62, 0.006 );
		int lateral = add_vein( &l, 2, primary[0], &proposed, 2.0 * l.margin );
		free( proposed.p );
		proposed = grow( &l, at, side * 78.0, side * 45.0, 0.3, 0.006 );
		add_vein( &l, 2, primary[0], &proposed, 2.0 * l.margin );
		free( proposed.p );
		if ( lateral >= 0 )
		{
			secondaries( &l, lateral, 3, 3, 0.3, 0.75, 50.0, 20.0, 0.25, side );
		}
	}
	secondaries( &l, primary[0], 2, 4, 0.42, 0.85, 52.0, 15.0, 0.4, 0 );
	write_leaf( &l, folder, 0, 0 );
}

/* Cucumber (Cucumis sativus), seed 003: palmate with five shallow, angular, pointed lobes, a
 * deep heart-shaped sinus at the petiole and small teeth all round; five primaries. */
static void cucumber( const char* folder )
{
	static const palmate cucumber = { .name = "cucumber",
									  .disc = 0.44,
									  .sinus_half = 12.0,
									  .disc_teeth = 1.0,
									  .teeth_from = 0.0,
									  .lobes = { { 0.0, 1.0, 0.3, 0.42, 0.2, 1.25, 0.0, 0.0, 1.0 },
												 { 62.0, 0.9, 0.3, 0.4, 0.2, 1.25, 0.0, 6.0, 1.0 },
												 { 126.0, 0.55, 0.26, 0.3, 0.2, 1.1, 0.0, 12.0, 1.0 } },
									  .outline = 2400,
									  .teeth = { 0.04, 0.01, 0.6, 0.0 },
									  .count = 4,
									  .count_basal = 3,
									  .veins = { 0.2, 0.8, 52.0, 18.0, 0.3 },
									  .table_n = 0,
									  .table_b = 0 };
	palmate_leaf( folder, &cucumber );
}

/* A lobule: a lobe starting at fraction `at` along lobe parent's axis. */
static lobe lobule( const blade* b, int parent, double at, double turn, double length, double width, double tip )
{
	const lobe* p = b->lobes + parent;
	return ( lobe ){ .at = at,
					 .angle = p->angle + p->bend * at + turn,
					 .bend = -0.25 * turn,
					 .length = length,
					 .neck = 0.6 * width,
					 .width = width,
					 .peak = 0.5,
					 .taper = 0.6,
					 .tip = tip,
					 .swell = 1.0,
					 .teeth = 0.0,
					 .parent = parent };
}

/* Watermelon (Citrullus lanatus), seed 003: palmate, three (to five) lobes cut almost to the
 * midrib, each again deeply pinnately lobed into rounded lobules; a vein runs into every
 * lobe and lobule. */
static void watermelon( const char* folder )
{
	static blade b;
	b = ( blade ){ .junction = v2( 0.0, 0.0 ), .disc = 0.1, .blend = 0.04, .cut = -INFINITY };
	const double angle[3] = { 0.0, 64.0, 128.0 }, len[3] = { 1.0, 0.88, 0.52 };
	int main_lobes = 0;
	for ( int k = 0; k < 3; ++k )
	{
		for ( int side = 1; side >= ( k == 0 ? 1 : -1 ); side -= 2 )
		{
			lobe m = palm( &b, side * angle[k], len[k], 0.055, 0.072, 0.5, 0.6, 0.055, k > 0 ? side * 10.0 : 0.0, 1.0 );
			m.teeth = 0.0;
			add_lobe( &b, m );
			main_lobes += 1;
		}
	}
	for ( int i = 0; i < main_lobes; ++i )
	{
		double l = b.lobes[i].length;
		int basal = i >= 3;
		for ( int side = 1; side >= -1; side -= 2 )
		{
			add_lobe( &b, lobule( &b, i, basal ? 0.5 : 0.3, side * 62.0, ( basal ? 0.5 : 0.36 ) * l, 0.078, 0.065 ) );
			if ( !basal )
			{
				add_lobe( &b, lobule( &b, i, 0.64, side * 55.0, 0.26 * l, 0.068, 0.055 ) );
			}
		}
	}
	leaf l = new_leaf( "watermelon", 0.02, 0.012 );
	make_outline( &l, blade_field, &b, b.junction, 2800 );
	int primary[MAX_LOBES];
	primaries( &l, &b, primary, 0.008 );
	write_leaf( &l, folder, 0, 0 );
}

/* Ginkgo: a fan between two straight edges from the petiole, its rim wavy and split in the
 * middle by a notch. */
typedef struct fan
{
	double half_angle; /* of the wedge, degrees */
	double radius;
	double round; /* smooth intersection width: rounds the corners and the base */
	double notch; /* depth of the central notch from the rim */
	double notch_half;
	double wave; /* relative undulation of the rim */
} fan;

static double fan_field( const void* shape, vec2 p )
{
	const fan* g = shape;
	double a = g->half_angle * PI / 180.0;
	double wedge = fabs( p.x ) * cos( a ) - p.y * sin( a );
	double theta = atan2( -p.x, p.y );
	double rim = g->radius * ( 1.0 + g->wave * ( sin( 7.0 * theta + 0.4 ) + 0.5 * sin( 17.0 * theta ) ) );
	double f = -smooth_min( -wedge, -( length( p ) - rim ), g->round );
	double b = g->notch_half * PI / 180.0;
	double notch = fabs( p.x ) * cos( b ) - ( p.y - ( g->radius - g->notch ) ) * sin( b );
	return -smooth_min( -f, notch, 0.3 * g->round );
}

/* Forks vein `parent` into two straight veins from its end, each heading for the middle of one
 * half of the parent's sector [lo, hi] (degrees about the fan's apex) at radius radii[0]; they
 * fork again while radii are left, so the veins spread evenly over the fan. */
static void dichotomy( leaf* l, int parent, double lo, double hi, const double* radii, int levels )
{
	const path* pv = &l->veins[parent].points;
	vec2 from = pv->p[pv->count - 1];
	vec2 apex = to_leaf( l, v2( 0.0, 0.0 ) );
	for ( int half = 0; half < 2; ++half )
	{
		double a = half == 0 ? lo : 0.5 * ( lo + hi ), b = half == 0 ? 0.5 * ( lo + hi ) : hi;
		double a1 = 0.5 * ( a + b ), r1 = radii[0] * l->scale;
		path proposed = line( from, add( apex, mul( heading( a1 ), r1 ) ), 0.006 );
		int v = add_vein( l, l->veins[parent].order + 1, parent, &proposed, 2.0 * l->margin );
		int whole = v >= 0 && l->veins[v].points.count == proposed.count;
		free( proposed.p );
		if ( whole && levels > 1 )
		{
			dichotomy( l, v, a, b, radii + 1, levels - 1 );
		}
	}
}

/* Ginkgo (Ginkgo biloba), Fig. 17 row 5: a fan with a wavy rim and a central notch, narrowing
 * to the petiole; dichotomous venation, every vein forking in two again and again. */
static void ginkgo( const char* folder )
{
	static fan g = {
		.half_angle = 56.0, .radius = 1.0, .round = 0.12, .notch = 0.24, .notch_half = 5.0, .wave = 0.012
	};
	leaf l = new_leaf( "ginkgo", 0.02, 0.01 );
	l.start = 0.08; /* forks part at a narrow angle */
	make_outline( &l, fan_field, &g, v2( 0.0, 0.2 ), 2400 );
	path stem = line( v2( 0.0, 0.0 ), to_leaf( &l, v2( 0.0, 0.14 ) ), 0.006 );
	int root = add_vein( &l, 1, -1, &stem, 0.0 );
	free( stem.p );
	if ( root < 0 )
	{
		die( "no vein fits the petiole", l.name );
	}
	const double radii[5] = { 0.34, 0.5, 0.64, 0.78, 2.0 };
	dichotomy( &l, root, -50.0, 50.0, radii, 5 );
	write_leaf( &l, folder, 0, 0 );
}

/* A grass blade: long and narrow, cut square where it leaves the sheath, tapering to a fine
 * point; parallel veins that start at the base, keep their share of the width and end one
 * after another as the blade narrows to the tip, the midvein last. */
static void grass( const char* folder )
{
	static blade b;
	b = ( blade ){ .junction = v2( 0.0, 0.02 ), .blend = 0.05, .cut = 0.0 };
	lobe blade_lobe = simple_blade( 0.034, 0.038, 0.18, 0.75, 1.0 );
	blade_lobe.start = b.junction;
	add_lobe( &b, blade_lobe );
	/* Margins relative to the blade's width: 2% of its length would leave no room. */
	leaf l = new_leaf( "grass", 0.006, 0.005 );
	l.start = 0.04;
	make_outline( &l, blade_field, &b, b.junction, 1600 );
	int primary[MAX_LOBES];
	primaries( &l, &b, primary, 0.008 );
	const lobe* lobe = b.lobes;
	const double lanes[4] = { 0.36, -0.36, 0.7, -0.7 };
	for ( int k = 0; k < 4; ++k )
	{
		path proposed = { 0 };
		push( &proposed, l.veins[primary[0]].points.p[0] );
		for ( double y = 0.012; y < 1.0; y += 0.006 )
		{
			double t = fmax( 0.0, ( y - lobe->start.y ) / lobe->length );
			/* Fan out from the base over the first few hundredths, then run parallel. */
			double x = lanes[k] * lobe_width( lobe, t ) * smoothstep( 0.0, 0.035, y );
			push( &proposed, to_leaf( &l, v2( x, y ) ) );
		}
		add_vein( &l, 2, primary[0], &proposed, 2.0 * l.margin );
		free( proposed.p );
	}
	write_leaf( &l, folder, 0, 0 );
}

int main( int argc, char** argv )
{
	const char* folder = argc > 1 ? argv[1] : "data/leaves";
	maple( folder );
	plane( folder );
	wisteria( folder );
	hibiscus( folder );
	ginkgo( folder );
	grass( folder );
	hickory( folder );
	cucumber( folder );
	watermelon( folder );
	return 0;
}
