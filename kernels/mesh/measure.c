/* _GNU_SOURCE: sched_getaffinity for core/internal/team.h. */
#define _GNU_SOURCE

#include "mesh/measure.h"

#include "core/array.h"
#include "core/internal/team.h"
#include "mesh/internal/measure_shared.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* ---------------------------------------------------------------------------------------------
 * Shape measures */

sere_shape_input sere_shape_input_default( void )
{
	sere_shape_input in;
	memset( &in, 0, sizeof( in ) );
	in.ground = -INFINITY;
	in.wrinkle_threshold = 0.05;
	in.band = 0.03;
	in.main_order = 2;
	return in;
}

sere_status sere_measure_validate( const sere_shape_input* in )
{
	if ( in == NULL || in->x == NULL || in->y == NULL || in->z == NULL || in->u == NULL || in->v == NULL ||
		 in->tri == NULL || in->edge_a == NULL || in->edge_b == NULL || in->boundary == NULL ||
		 !sere_threads_valid( in->threads ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	if ( in->veins != NULL )
	{
		/* every vein's points inside vein_xy, which must be finite (the measures walk them) */
		const sere_leaf_shape* s = in->veins;
		if ( in->main_order < 1 || s->vein_count < 0 || s->vein_point_count < 0 ||
			 ( s->vein_count > 0 && s->veins == NULL ) || ( s->vein_point_count > 0 && s->vein_xy == NULL ) )
		{
			return SERE_ERR_ARGUMENT;
		}
		for ( int32_t k = 0; k < s->vein_count; ++k )
		{
			const sere_vein* vein = s->veins + k;
			if ( vein->first < 0 || vein->count < 0 || (int64_t) vein->first + vein->count > s->vein_point_count )
			{
				return SERE_ERR_ARGUMENT;
			}
		}
		for ( int64_t i = 0; i < 2 * (int64_t) s->vein_point_count; ++i )
		{
			if ( !isfinite( s->vein_xy[i] ) )
			{
				return SERE_ERR_NONFINITE;
			}
		}
	}
	if ( in->vertex_count <= 0 || in->triangle_count <= 0 || in->edge_count <= 0 || in->midvein_count < 0 ||
		 ( in->midvein_count > 0 && in->midvein == NULL ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	/* -inf is "no ground"; a NaN or +inf ground is a mistake, not a choice */
	if ( isnan( in->ground ) || in->ground == INFINITY || !( in->wrinkle_threshold >= 0.0 ) ||
		 !isfinite( in->wrinkle_threshold ) || !( in->band > 0.0 ) || !isfinite( in->band ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	if ( !sere_array_indices_valid( in->tri, 3 * (int64_t) in->triangle_count, in->vertex_count ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	for ( int32_t e = 0; e < in->edge_count; ++e )
	{
		if ( in->edge_a[e] < 0 || in->edge_a[e] >= in->vertex_count || in->edge_b[e] < 0 ||
			 in->edge_b[e] >= in->vertex_count || in->edge_a[e] == in->edge_b[e] )
		{
			return SERE_ERR_ARGUMENT;
		}
	}
	if ( !sere_array_indices_valid( in->midvein, in->midvein_count, in->vertex_count ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	const float* coordinates[] = { in->x, in->y, in->z, in->u, in->v };
	return sere_array_finite( coordinates, 5, in->vertex_count, in->threads ) ? SERE_OK : SERE_ERR_NONFINITE;
}

typedef struct edge_key
{
	uint64_t key;
	int32_t edge;
} edge_key;

static int compare_edge_key( const void* a, const void* b )
{
	uint64_t u = ( (const edge_key*) a )->key, v = ( (const edge_key*) b )->key;
	return ( u > v ) - ( u < v );
}

static inline uint64_t pair_key( int32_t i, int32_t j )
{
	uint32_t lo = (uint32_t) ( i < j ? i : j ), hi = (uint32_t) ( i < j ? j : i );
	return ( (uint64_t) lo << 32 ) | hi;
}

/* edge_tri[2 e] is the triangle running along edge e from edge_a to edge_b (counter-clockwise),
 * edge_tri[2 e + 1] the one running back, −1 where there is none; tri_edge[3 t + k] is the edge
 * from corner k to corner k + 1 of triangle t. */
static sere_status shape_adjacency( const sere_shape_input* in, int32_t* edge_tri, int32_t* tri_edge )
{
	int32_t ec = in->edge_count;
	edge_key* keys = malloc( sizeof( edge_key ) * (size_t) ec );
	if ( keys == NULL )
	{
		return SERE_ERR_MEMORY;
	}
	for ( int32_t e = 0; e < ec; ++e )
	{
		keys[e] = ( edge_key ){ pair_key( in->edge_a[e], in->edge_b[e] ), e };
		edge_tri[2 * e] = -1, edge_tri[2 * e + 1] = -1;
	}
	qsort( keys, (size_t) ec, sizeof( edge_key ), compare_edge_key );
	sere_status status = SERE_OK;
	for ( int32_t e = 1; e < ec && status == SERE_OK; ++e )
	{
		if ( keys[e].key == keys[e - 1].key )
		{
			status = SERE_ERR_ARGUMENT; /* an edge listed twice */
		}
	}
	for ( int32_t t = 0; t < in->triangle_count && status == SERE_OK; ++t )
	{
		for ( int k = 0; k < 3 && status == SERE_OK; ++k )
		{
			int32_t i = in->tri[3 * (size_t) t + k], j = in->tri[3 * (size_t) t + ( k + 1 ) % 3];
			uint64_t key = pair_key( i, j );
			int32_t lo = 0, hi = ec;
			while ( lo < hi )
			{
				int32_t mid = lo + ( hi - lo ) / 2;
				if ( keys[mid].key < key )
				{
					lo = mid + 1;
				}
				else
				{
					hi = mid;
				}
			}
			if ( lo == ec || keys[lo].key != key )
			{
				status = SERE_ERR_ARGUMENT; /* a triangle edge missing from the list */
				break;
			}
			int32_t e = keys[lo].edge;
			int32_t slot = i == in->edge_a[e] ? 0 : 1;
			if ( edge_tri[2 * e + slot] != -1 )
			{
				status = SERE_ERR_GEOMETRY;
				break;
			}
			edge_tri[2 * e + slot] = t;
			tri_edge[3 * (size_t) t + k] = e;
		}
	}
	free( keys );
	return status;
}

/* The corners a, b, c of triangle t and n = (b − a) × (c − a): twice its area times its unit
 * normal. */
static void triangle_corners( const sere_shape_input* in, int32_t t, double a[3], double b[3], double c[3],
							  double n[3] )
{
	const int32_t* v = in->tri + 3 * (size_t) t;
	double ab[3], ac[3];
	sere_measure_position( in, v[0], a );
	sere_measure_position( in, v[1], b );
	sere_measure_position( in, v[2], c );
	sub3( b, a, ab );
	sub3( c, a, ac );
	cross3( ab, ac, n );
}

static void triangle_cross( const sere_shape_input* in, int32_t t, double n[3] )
{
	double a[3], b[3], c[3];
	triangle_corners( in, t, a, b, c, n );
}

void sere_measure_unit_normal( const sere_shape_input* in, int32_t t, double n[3] )
{
	triangle_cross( in, t, n );
	double length = sqrt( dot3( n, n ) );
	for ( int k = 0; k < 3; ++k )
	{
		n[k] = length > 0.0 ? n[k] / length : 0.0;
	}
}

static void dihedrals( const sere_shape_input* in, const int32_t* edge_tri, double* dihedral )
{
	for ( int32_t e = 0; e < in->edge_count; ++e )
	{
		int32_t t0 = edge_tri[2 * e], t1 = edge_tri[2 * e + 1];
		if ( t0 < 0 || t1 < 0 )
		{
			dihedral[e] = 0.0;
			continue;
		}
		double n0[3], n1[3], a[3], b[3], axis[3], w[3];
		sere_measure_unit_normal( in, t0, n0 );
		sere_measure_unit_normal( in, t1, n1 );
		sere_measure_position( in, in->edge_a[e], a );
		sere_measure_position( in, in->edge_b[e], b );
		sub3( b, a, axis );
		double length = sqrt( dot3( axis, axis ) );
		/* t0 runs a → b, so turning n0 into n1 about a → b by a positive angle lifts t1 to the
		 * side n0 points to: the surface folds towards its normals */
		cross3( n1, n0, w );
		dihedral[e] = length > 0.0 ? atan2( dot3( w, axis ) / length, dot3( n0, n1 ) ) : 0.0;
	}
}

sere_status sere_shape_dihedrals( const sere_shape_input* in, double* dihedral )
{
	sere_status status = sere_measure_validate( in );
	if ( status != SERE_OK || dihedral == NULL )
	{
		return status != SERE_OK ? status : SERE_ERR_ARGUMENT;
	}
	int32_t* edge_tri = malloc( sizeof( int32_t ) * 2 * (size_t) in->edge_count );
	int32_t* tri_edge = malloc( sizeof( int32_t ) * 3 * (size_t) in->triangle_count );
	status = edge_tri == NULL || tri_edge == NULL ? SERE_ERR_MEMORY : shape_adjacency( in, edge_tri, tri_edge );
	if ( status == SERE_OK )
	{
		dihedrals( in, edge_tri, dihedral );
	}
	free( edge_tri );
	free( tri_edge );
	return status;
}

/* Eigen decomposition of a symmetric 3 × 3 matrix m (not modified) by cyclic Jacobi rotations: eigenvalues in w
 * ascending, the unit eigenvector of w[k] in column k of v. Small and exact enough for the
 * covariance matrices of the plane and circle fits. */
static void eigen3( double m[3][3], double w[3], double v[3][3] )
{
	double a[3][3];
	memcpy( a, m, sizeof( a ) );
	for ( int i = 0; i < 3; ++i )
	{
		for ( int j = 0; j < 3; ++j )
		{
			v[i][j] = i == j ? 1.0 : 0.0;
		}
	}
	static const int pairs[3][2] = { { 0, 1 }, { 0, 2 }, { 1, 2 } };
	for ( int sweep = 0; sweep < 64; ++sweep )
	{
		double off = fabs( a[0][1] ) + fabs( a[0][2] ) + fabs( a[1][2] );
		double diag = fabs( a[0][0] ) + fabs( a[1][1] ) + fabs( a[2][2] );
		if ( off <= 1e-300 || off <= 1e-18 * diag )
		{
			break;
		}
		for ( int r = 0; r < 3; ++r )
		{
			int p = pairs[r][0], q = pairs[r][1];
			if ( a[p][q] == 0.0 )
			{
				continue;
			}
			double theta = ( a[q][q] - a[p][p] ) / ( 2.0 * a[p][q] );
			double t = fabs( theta ) > 1e150
						   ? 0.5 / theta
						   : ( theta >= 0.0 ? 1.0 : -1.0 ) / ( fabs( theta ) + sqrt( theta * theta + 1.0 ) );
			double c = 1.0 / sqrt( t * t + 1.0 ), s = t * c;
			for ( int k = 0; k < 3; ++k )
			{
				double kp = a[k][p], kq = a[k][q];
				a[k][p] = c * kp - s * kq, a[k][q] = s * kp + c * kq;
			}
			for ( int k = 0; k < 3; ++k )
			{
				double pk = a[p][k], qk = a[q][k];
				a[p][k] = c * pk - s * qk, a[q][k] = s * pk + c * qk;
			}
			for ( int k = 0; k < 3; ++k )
			{
				double kp = v[k][p], kq = v[k][q];
				v[k][p] = c * kp - s * kq, v[k][q] = s * kp + c * kq;
			}
		}
	}
	int order[3] = { 0, 1, 2 };
	for ( int i = 0; i < 3; ++i )
	{
		for ( int j = i + 1; j < 3; ++j )
		{
			if ( a[order[j]][order[j]] < a[order[i]][order[i]] )
			{
				int swap = order[i];
				order[i] = order[j], order[j] = swap;
			}
		}
	}
	double vv[3][3];
	for ( int k = 0; k < 3; ++k )
	{
		w[k] = a[order[k]][order[k]];
		for ( int i = 0; i < 3; ++i )
		{
			vv[i][k] = v[i][order[k]];
		}
	}
	memcpy( v, vv, sizeof( vv ) );
}

/* Mean and covariance of the selected points: every vertex i with select == NULL or select[i]
 * == want, or the listed indices when list != NULL. Returns the point count. */
static int32_t point_moments( const sere_shape_input* in, const uint8_t* select, int want, const int32_t* list,
							  int32_t list_count, double mean[3], double cov[3][3] )
{
	int32_t n = list != NULL ? list_count : in->vertex_count;
	int32_t used = 0;
	double sum[3] = { 0.0, 0.0, 0.0 };
	for ( int32_t k = 0; k < n; ++k )
	{
		int32_t i = list != NULL ? list[k] : k;
		if ( select != NULL && ( select[i] != 0 ) != want )
		{
			continue;
		}
		double p[3];
		sere_measure_position( in, i, p );
		for ( int a = 0; a < 3; ++a )
		{
			sum[a] += p[a];
		}
		used += 1;
	}
	memset( cov, 0, sizeof( double ) * 9 );
	for ( int a = 0; a < 3; ++a )
	{
		mean[a] = used > 0 ? sum[a] / used : 0.0;
	}
	/* second pass about the mean: no cancellation for a leaf far from the origin */
	for ( int32_t k = 0; k < n; ++k )
	{
		int32_t i = list != NULL ? list[k] : k;
		if ( select != NULL && ( select[i] != 0 ) != want )
		{
			continue;
		}
		double p[3], d[3];
		sere_measure_position( in, i, p );
		sub3( p, mean, d );
		for ( int a = 0; a < 3; ++a )
		{
			for ( int b = 0; b < 3; ++b )
			{
				cov[a][b] += d[a] * d[b];
			}
		}
	}
	return used;
}

static double margin_lift( const sere_shape_input* in, const double mean_normal[3] )
{
	double mean[3], cov[3][3], w[3], v[3][3];
	int32_t interior = point_moments( in, in->boundary, 0, NULL, 0, mean, cov );
	if ( interior < 3 || interior == in->vertex_count )
	{
		return NAN;
	}
	eigen3( cov, w, v );
	double n[3] = { v[0][0], v[1][0], v[2][0] }; /* least variance: the plane's normal */
	if ( dot3( n, mean_normal ) < 0.0 )
	{
		n[0] = -n[0], n[1] = -n[1], n[2] = -n[2];
	}
	double sum = 0.0;
	int32_t count = 0;
	for ( int32_t i = 0; i < in->vertex_count; ++i )
	{
		if ( in->boundary[i] != 0 )
		{
			double p[3], d[3];
			sere_measure_position( in, i, p );
			sub3( p, mean, d );
			sum += dot3( n, d );
			count += 1;
		}
	}
	return sum / count;
}

/* Solves the 3 × 3 system m x = r by Gaussian elimination with partial pivoting; false when a
 * pivot vanishes. */
static bool solve3( double m[3][3], double r[3], double x[3] )
{
	for ( int col = 0; col < 3; ++col )
	{
		int pivot = col;
		for ( int row = col + 1; row < 3; ++row )
		{
			if ( fabs( m[row][col] ) > fabs( m[pivot][col] ) )
			{
				pivot = row;
			}
		}
		if ( !( fabs( m[pivot][col] ) > 0.0 ) )
		{
			return false;
		}
		for ( int k = 0; k < 3; ++k )
		{
			double swap = m[col][k];
			m[col][k] = m[pivot][k], m[pivot][k] = swap;
		}
		double swap = r[col];
		r[col] = r[pivot], r[pivot] = swap;
		for ( int row = col + 1; row < 3; ++row )
		{
			double f = m[row][col] / m[col][col];
			for ( int k = col; k < 3; ++k )
			{
				m[row][k] -= f * m[col][k];
			}
			r[row] -= f * r[col];
		}
	}
	for ( int row = 2; row >= 0; --row )
	{
		double s = r[row];
		for ( int k = row + 1; k < 3; ++k )
		{
			s -= m[row][k] * x[k];
		}
		x[row] = s / m[row][row];
	}
	return true;
}

static double midvein_curvature( const sere_shape_input* in )
{
	if ( in->midvein == NULL || in->midvein_count < 3 )
	{
		return 0.0;
	}
	double mean[3], cov[3][3], w[3], v[3][3];
	point_moments( in, NULL, 0, in->midvein, in->midvein_count, mean, cov );
	eigen3( cov, w, v );
	/* Points in a line within rounding of float positions (relative variance ~1e-14) bend
	 * nowhere; a real bend of sagitta s over length L has a variance ratio of order (s / L)². */
	if ( !( w[1] > 1e-12 * w[2] ) )
	{
		return 0.0;
	}
	/* coordinates in the best plane, scaled to unit spread so the fit is well conditioned */
	double scale = sqrt( w[2] / in->midvein_count );
	double e1[3] = { v[0][2], v[1][2], v[2][2] }, e2[3] = { v[0][1], v[1][1], v[2][1] };
	/* Kåsa's algebraic fit: least squares of s² + t² + D s + E t + F over the points */
	double m[3][3] = { { 0.0 } }, r[3] = { 0.0, 0.0, 0.0 };
	for ( int32_t k = 0; k < in->midvein_count; ++k )
	{
		double p[3], d[3];
		sere_measure_position( in, in->midvein[k], p );
		sub3( p, mean, d );
		double row[3] = { dot3( d, e1 ) / scale, dot3( d, e2 ) / scale, 1.0 };
		double rhs = -( row[0] * row[0] + row[1] * row[1] );
		for ( int i = 0; i < 3; ++i )
		{
			for ( int j = 0; j < 3; ++j )
			{
				m[i][j] += row[i] * row[j];
			}
			r[i] += row[i] * rhs;
		}
	}
	double x[3];
	if ( !solve3( m, r, x ) )
	{
		return 0.0;
	}
	double radius2 = 0.25 * ( x[0] * x[0] + x[1] * x[1] ) - x[2];
	return radius2 > 0.0 ? 1.0 / ( sqrt( radius2 ) * scale ) : 0.0;
}

/* Largest squared distance over all vertex pairs: an exact max, so any thread count agrees. */
static double diameter2( const sere_shape_input* in )
{
	int32_t n = in->vertex_count;
	const float *x = in->x, *y = in->y, *z = in->z;
	double best = 0.0;
#pragma omp parallel for num_threads( sere_team_for( in->threads ) ) schedule( dynamic, 32 ) reduction( max : best )
	for ( int32_t i = 0; i < n; ++i )
	{
		double xi = x[i], yi = y[i], zi = z[i];
		for ( int32_t j = i + 1; j < n; ++j )
		{
			double dx = x[j] - xi, dy = y[j] - yi, dz = z[j] - zi;
			double d2 = dx * dx + dy * dy + dz * dz;
			best = d2 > best ? d2 : best;
		}
	}
	return best;
}

/* The measures of sere_shape_input::pose_only, after validation: the pose, the extent and the
 * two cross-section rolls; the scratch arrays are the caller's. */
static void shape_pose( const sere_shape_input* in, int32_t* tris, double* lateral, sere_shape* out )
{
	int32_t tc = in->triangle_count;

	/* area, centroid and mean normal: sums over triangles of area-weighted quantities */
	double area = 0.0, moment[3] = { 0.0, 0.0, 0.0 }, normal[3] = { 0.0, 0.0, 0.0 };
	for ( int32_t t = 0; t < tc; ++t )
	{
		double a[3], b[3], c[3], n[3];
		triangle_corners( in, t, a, b, c, n );
		double at = 0.5 * sqrt( dot3( n, n ) );
		for ( int k = 0; k < 3; ++k )
		{
			moment[k] += at * ( ( a[k] + b[k] + c[k] ) / 3.0 );
			normal[k] += 0.5 * n[k]; /* area · unit normal */
		}
		area += at;
	}
	out->area = area;
	for ( int k = 0; k < 3; ++k )
	{
		out->centroid[k] = area > 0.0 ? moment[k] / area : 0.0;
		out->mean_normal[k] = area > 0.0 ? normal[k] / area : 0.0;
	}
	out->flip = out->mean_normal[2] < 0.0;
	out->extent = in->skip_extent ? NAN : sqrt( diameter2( in ) );

	double min_z = INFINITY, max_z = -INFINITY;
	for ( int32_t i = 0; i < in->vertex_count; ++i )
	{
		min_z = fmin( min_z, in->z[i] ), max_z = fmax( max_z, in->z[i] );
	}
	out->min_z = min_z, out->max_z = max_z;
	out->ground_gap = in->ground == -INFINITY ? NAN : min_z - in->ground;
	out->roll_tip = sere_measure_band_roll( in, 0.85, tris, lateral );
	out->roll_base = sere_measure_band_roll( in, 0.25, tris, lateral );
}

/* Every measure but the pose and the rolls: those of the edges and their dihedrals, the margin,
 * the curls and the midvein. */
static void shape_form( const sere_shape_input* in, const int32_t* edge_tri, const int32_t* tri_edge, double* dihedral,
						sere_shape* out )
{
	int32_t ec = in->edge_count, tc = in->triangle_count;

	/* creases: mean |dihedral| over interior edges, veins apart */
	dihedrals( in, edge_tri, dihedral );
	double vein_sum = 0.0, surf_sum = 0.0;
	for ( int32_t e = 0; e < ec; ++e )
	{
		if ( edge_tri[2 * e] < 0 || edge_tri[2 * e + 1] < 0 )
		{
			continue;
		}
		if ( in->edge_vein != NULL && in->edge_vein[e] != 0 )
		{
			vein_sum += fabs( dihedral[e] ), out->vein_edges += 1;
		}
		else
		{
			surf_sum += fabs( dihedral[e] ), out->surf_edges += 1;
		}
	}
	out->crease_vein = out->vein_edges > 0 ? vein_sum / out->vein_edges : 0.0;
	out->crease_surf = out->surf_edges > 0 ? surf_sum / out->surf_edges : 0.0;

	/* wrinkles: a ridge and a valley meeting in one triangle */
	int64_t changes = 0;
	for ( int32_t t = 0; t < tc; ++t )
	{
		int sign[3];
		for ( int k = 0; k < 3; ++k )
		{
			int32_t e = tri_edge[3 * (size_t) t + k];
			bool interior = edge_tri[2 * e] >= 0 && edge_tri[2 * e + 1] >= 0;
			double d = dihedral[e];
			sign[k] = !interior || !( fabs( d ) > in->wrinkle_threshold ) ? 0 : ( d > 0.0 ? 1 : -1 );
		}
		changes += ( sign[0] * sign[1] < 0 ) + ( sign[1] * sign[2] < 0 ) + ( sign[2] * sign[0] < 0 );
	}
	out->wrinkle_sign_changes = changes;

	out->margin_lift = margin_lift( in, out->mean_normal );
	out->curl_tip = sere_measure_axis_curl( in, 0.55, 0.93 );
	out->curl_base = sere_measure_axis_curl( in, 0.07, 0.45 );
	out->midvein_curvature = midvein_curvature( in );
}

/* What sere_shape_input::pose_only leaves unmeasured. */
static void shape_form_unmeasured( sere_shape* out )
{
	out->crease_vein = out->crease_surf = NAN;
	out->vein_edges = out->surf_edges = -1;
	out->wrinkle_sign_changes = -1;
	out->margin_lift = NAN;
	out->curl_tip = out->curl_base = NAN;
	out->crease_main = out->crease_blade = NAN;
	out->vein_roll_tip = out->vein_roll_base = NAN;
	out->midvein_curvature = NAN;
}

sere_status sere_shape_measure( const sere_shape_input* in, sere_shape* out )
{
	if ( out == NULL )
	{
		return SERE_ERR_ARGUMENT;
	}
	memset( out, 0, sizeof( *out ) );
	sere_status status = sere_measure_validate( in );
	if ( status != SERE_OK )
	{
		return status;
	}
	const bool form = !in->pose_only;
	int32_t* tris = malloc( sizeof( int32_t ) * (size_t) in->triangle_count );
	double* lateral = malloc( sizeof( double ) * (size_t) in->triangle_count );
	int32_t* edge_tri = form ? malloc( sizeof( int32_t ) * 2 * (size_t) in->edge_count ) : NULL;
	int32_t* tri_edge = form ? malloc( sizeof( int32_t ) * 3 * (size_t) in->triangle_count ) : NULL;
	double* dihedral = form ? malloc( sizeof( double ) * (size_t) in->edge_count ) : NULL;
	if ( tris == NULL || lateral == NULL || ( form && ( edge_tri == NULL || tri_edge == NULL || dihedral == NULL ) ) )
	{
		status = SERE_ERR_MEMORY;
	}
	else if ( form )
	{
		status = shape_adjacency( in, edge_tri, tri_edge );
	}
	if ( status == SERE_OK )
	{
		shape_pose( in, tris, lateral, out );
		if ( !form )
		{
			shape_form_unmeasured( out );
		}
		else
		{
			shape_form( in, edge_tri, tri_edge, dihedral, out );
			if ( !sere_measure_main_veins( in, edge_tri, dihedral, out ) )
			{
				status = SERE_ERR_MEMORY;
			}
		}
	}
	free( edge_tri );
	free( tri_edge );
	free( dihedral );
	free( tris );
	free( lateral );
	return status;
}
