#include "core/geometry.h"

#include <math.h>

int sere_point_in_polygon( const double* xy, int32_t count, double px, double py )
{
	int inside = 0;
	for ( int32_t i = 0, j = count - 1; i < count; j = i++ )
	{
		double xi = xy[2 * i], yi = xy[2 * i + 1], xj = xy[2 * j], yj = xy[2 * j + 1];
		if ( ( yi > py ) != ( yj > py ) && px < xj + ( py - yj ) * ( xi - xj ) / ( yi - yj ) )
		{
			inside = !inside;
		}
	}
	return inside;
}

double sere_polygon_area( const double* xy, int32_t count )
{
	double twice = 0.0;
	for ( int32_t i = 0, j = count - 1; i < count; j = i++ )
	{
		twice += xy[2 * j] * xy[2 * i + 1] - xy[2 * i] * xy[2 * j + 1];
	}
	return 0.5 * twice;
}

void sere_segment_offset( const double* p, const double* a, const double* b, double* dx, double* dy )
{
	double ex = b[0] - a[0], ey = b[1] - a[1];
	double length2 = ex * ex + ey * ey;
	double t = length2 > 0.0 ? ( ( p[0] - a[0] ) * ex + ( p[1] - a[1] ) * ey ) / length2 : 0.0;
	t = fmin( 1.0, fmax( 0.0, t ) );
	*dx = a[0] + t * ex - p[0];
	*dy = a[1] + t * ey - p[1];
}

double sere_point_segment_distance( const double* p, const double* a, const double* b )
{
	double dx, dy;
	sere_segment_offset( p, a, b, &dx, &dy );
	return hypot( dx, dy );
}
