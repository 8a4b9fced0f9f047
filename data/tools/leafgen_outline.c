/* leafgen — the blade: lobe fields, marching squares, the outline and its teeth (see leafgen.c). */
#include "leafgen.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

void die( const char* what, const char* name )
{
	fprintf( stderr, "leafgen: %s: %s\n", name, what );
	exit( 1 );
}

void push( path* path, vec2 p )
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

double lobe_width( const lobe* l, double t )
{
	if ( t <= l->peak )
	{
		double rise = sin( 0.5 * PI * t / l->peak );
		return l->neck + ( l->width - l->neck ) * pow( rise, l->swell );
	}
	double u = ( t - l->peak ) / ( 1.0 - l->peak );
	return l->tip + ( l->width - l->tip ) * pow( cos( 0.5 * PI * u ), l->taper );
}

void lobe_build( lobe* l )
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
double blade_field( const void* shape, vec2 p )
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
double blade_teeth( const void* shape, vec2 p, double* tipward )
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

double polygon_area( const path* poly )
{
	double twice = 0.0;
	for ( int i = 0, j = poly->count - 1; i < poly->count; j = i++ )
	{
		twice += cross( poly->p[j], poly->p[i] );
	}
	return 0.5 * twice;
}

double polygon_perimeter( const path* poly )
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
path resample( const path* poly, double start, int count )
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

vec2 to_leaf( const leaf* l, vec2 p )
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

vec2 quantized( vec2 p )
{
	return v2( quantize( p.x ), quantize( p.y ) );
}

/* Traces the blade, starts the outline at the base (straight below the junction), scales the
 * leaf so its larger side is one unit with the base at the origin, and resamples it to count
 * points. */
void make_outline( leaf* l, field_fn* field, const void* shape, vec2 junction, int count )
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
void serrate( leaf* l, teeth_fn* teeth, const void* shape, double wavelength, double depth, double duty, double fine )
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
