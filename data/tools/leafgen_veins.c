/* leafgen — the veins: clipping against the outline and each other, primaries and
 * secondaries, and writing the .leaf file (see leafgen.c). */
#include "leafgen.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

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
int add_vein( leaf* l, int order, int parent, const path* proposed, double shortest )
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
path line( vec2 a, vec2 b, double step )
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
path grow( const leaf* l, vec2 start, double angle, double final, double reach, double step )
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
void secondaries( leaf* l, int parent, int order, int count, double lo, double hi, double angle, double final,
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

void write_leaf( leaf* l, const char* folder, int table_n, int table_b )
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

void add_lobe( blade* b, lobe lobe )
{
	if ( lobe.parent >= 0 )
	{
		lobe.start = b->lobes[lobe.parent].axis[(int) round( lobe.at * LOBE_STEPS )];
	}
	lobe_build( &lobe );
	b->lobes[b->lobe_count++] = lobe;
}

/* A lobe from the junction: heading, length, neck, width, peak, taper, tip, bend. */
lobe palm( const blade* b, double angle, double length, double neck, double width, double peak, double taper,
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
int primaries( leaf* l, const blade* b, int* primary, double step )
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

leaf new_leaf( const char* name, double margin, double gap )
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
void add_palm_pair( blade* b, double angle, double length, double neck, double width, double peak, double taper,
					double tip, double bend, double swell )
{
	for ( int side = 1; side >= -1; side -= 2 )
	{
		add_lobe( b, palm( b, side * angle, length, neck, width, peak, taper, tip, side * bend, swell ) );
	}
}

/* A primary up every lobe and third-order secondaries on each: `count` on the first three
 * lobes (the middle one and its neighbours), `count_basal` on the others. */
void lobe_veins( leaf* l, const blade* b, int count, int count_basal, double lo, double hi, double angle, double final,
				 double reach )
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
