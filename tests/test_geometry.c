/* The shared plane geometry (kernels/core/geometry.c): cases whose answers are exact in binary. */
#include "core/geometry.h"

#include <criterion/criterion.h>
#include <math.h>

/* The unit square, counterclockwise, and the same square clockwise. */
static const double kSquare[8] = { 0, 0, 1, 0, 1, 1, 0, 1 };
static const double kSquareCw[8] = { 0, 0, 0, 1, 1, 1, 1, 0 };

Test( geometry, polygon_area_is_signed )
{
	/* every product is of small whole numbers: exact */
	cr_expect_eq( sere_polygon_area( kSquare, 4 ), 1.0 );
	cr_expect_eq( sere_polygon_area( kSquareCw, 4 ), -1.0 );
	const double triangle[6] = { 0, 0, 4, 0, 0, 3 };
	cr_expect_eq( sere_polygon_area( triangle, 3 ), 6.0 );
}

Test( geometry, point_in_polygon_even_odd )
{
	cr_expect( sere_point_in_polygon( kSquare, 4, 0.5, 0.5 ) );
	cr_expect( sere_point_in_polygon( kSquareCw, 4, 0.25, 0.75 ), "orientation does not matter" );
	cr_expect( !sere_point_in_polygon( kSquare, 4, 1.5, 0.5 ) );
	cr_expect( !sere_point_in_polygon( kSquare, 4, 0.5, -0.5 ) );
	/* a C shape: the notch (x in (1, 2), y in (1, 2)) is outside */
	const double c_shape[16] = { 0, 0, 3, 0, 3, 1, 1, 1, 1, 2, 3, 2, 3, 3, 0, 3 };
	cr_expect( !sere_point_in_polygon( c_shape, 8, 2.0, 1.5 ) );
	cr_expect( sere_point_in_polygon( c_shape, 8, 0.5, 1.5 ) );
	cr_expect( sere_point_in_polygon( c_shape, 8, 2.0, 0.5 ) );
}

Test( geometry, point_segment_distance_clamps_to_the_ends )
{
	const double a[2] = { 0, 0 }, b[2] = { 4, 0 };
	const double above[2] = { 1, 3 }, beyond[2] = { 7, 4 }, before[2] = { -3, -4 };
	cr_expect_eq( sere_point_segment_distance( above, a, b ), 3.0, "foot inside the segment" );
	cr_expect_eq( sere_point_segment_distance( beyond, a, b ), 5.0, "nearest is b (3-4-5)" );
	cr_expect_eq( sere_point_segment_distance( before, a, b ), 5.0, "nearest is a" );
	cr_expect_eq( sere_point_segment_distance( above, a, a ), hypot( 1.0, 3.0 ), "a point segment" );
	double dx, dy;
	sere_segment_offset( above, a, b, &dx, &dy );
	cr_expect( dx == 0.0 && dy == -3.0, "offset points from p to the segment: (%g, %g)", dx, dy );
}
