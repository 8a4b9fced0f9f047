/* leafgen — writes the shipped leaves, data/leaves/NAME.leaf: the species of the papers' figures
 * (seed 000 Fig. 17, seed 003's cucumber and watermelon) as outline, base and veins.
 *
 * Build and run from the repository root; the argument is the output folder:
 *   make build/leafgen && build/leafgen data/leaves
 * The program is three files: leafgen_outline.c traces and serrates the blade, leafgen_veins.c
 * grows the veins and writes the file, this one holds the species.
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
#include "leafgen.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

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
