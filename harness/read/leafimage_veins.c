/* sere harness — Vein placement: the vein skeleton walked from the base into polylines, cut at the margin. */
#include "core/geometry.h"
#include "read/leafimage_shared.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static int compare_tips( const void* pa, const void* pb )
{
	const tip* a = pa;
	const tip* b = pb;
	if ( a->length != b->length )
	{
		return a->length > b->length ? -1 : 1;
	}
	return ( a->index > b->index ) - ( a->index < b->index );
}

void leafimage_veins_work_free( veins_work* v )
{
	free( v->pixel ), free( v->component ), free( v->bfs_parent ), free( v->order_queue ), free( v->dist );
	free( v->children ), free( v->on_vein ), free( v->node_pos ), free( v->tips ), free( v->path );
	free( v->node_skeleton ), free( v->node_xy ), free( v->node_keep ), free( v->node_final ), free( v->veins );
	free( v->scratch ), free( v->stack );
}

static sere_status veins_work_create( veins_work* v, int32_t count )
{
	size_t n = (size_t) count + 1, nodes = 2 * n + 1;
	v->count = count;
	v->pixel = malloc( sizeof( int32_t ) * n );
	v->component = malloc( sizeof( int32_t ) * n );
	v->bfs_parent = malloc( sizeof( int32_t ) * n );
	v->order_queue = malloc( sizeof( int32_t ) * n );
	v->dist = malloc( sizeof( double ) * n );
	v->children = calloc( n, 1 );
	v->on_vein = malloc( sizeof( int32_t ) * n );
	v->node_pos = malloc( sizeof( int32_t ) * n );
	v->tips = malloc( sizeof( tip ) * n );
	v->path = malloc( sizeof( int32_t ) * n );
	v->node_skeleton = malloc( sizeof( int32_t ) * nodes );
	v->node_xy = malloc( sizeof( double ) * 2 * nodes );
	v->node_keep = calloc( nodes, 1 );
	v->node_final = malloc( sizeof( int32_t ) * nodes );
	v->veins = malloc( sizeof( vein_build ) * n );
	v->scratch = malloc( sizeof( double ) * 2 * nodes );
	v->stack = malloc( sizeof( int32_t ) * 2 * ( nodes + 1 ) );
	if ( v->pixel == NULL || v->component == NULL || v->bfs_parent == NULL || v->order_queue == NULL ||
		 v->dist == NULL || v->children == NULL || v->on_vein == NULL || v->node_pos == NULL || v->tips == NULL ||
		 v->path == NULL || v->node_skeleton == NULL || v->node_xy == NULL || v->node_keep == NULL ||
		 v->node_final == NULL || v->veins == NULL || v->scratch == NULL || v->stack == NULL )
	{
		return SERE_ERR_MEMORY;
	}
	return SERE_OK;
}

/* Visits the 8 neighbours of skeleton pixel s that are skeleton pixels. */
static int skeleton_neighbors( const reader* r, const veins_work* v, int32_t s, int32_t* out )
{
	int32_t p = v->pixel[s];
	int x = p % r->w, y = p / r->w, count = 0;
	for ( int dy = -1; dy <= 1; ++dy )
	{
		for ( int dx = -1; dx <= 1; ++dx )
		{
			int qx = x + dx, qy = y + dy;
			if ( ( dx != 0 || dy != 0 ) && qx >= 0 && qy >= 0 && qx < r->w && qy < r->h && r->region[qy * r->w + qx] )
			{
				out[count++] = r->queue[qy * r->w + qx];
			}
		}
	}
	return count;
}

static double pixel_distance( const reader* r, int32_t p, double x, double y )
{
	return hypot( p % r->w + 0.5 - x, p / r->w + 0.5 - y );
}

/* The veins' skeleton as trees rooted at the base: thins the strokes, checks every stroke reaches
 * the base, then splits each tree into polylines, longest first (tips in order of their path
 * length from the base; each walks back until it meets a vein already taken). */
/* The region array becomes the vein mask (red pixels of the silhouette), thinned to its
 * skeleton; the reader's queue then maps each pixel to its skeleton number (-1 for none).
 * Returns the number of skeleton pixels; *stroke_pixels is the number of stroke pixels. */
static int32_t number_skeleton_pixels( reader* r, int32_t* stroke_pixels )
{
	*stroke_pixels = 0;
	for ( int32_t i = 0; i < r->n; ++i )
	{
		uint8_t vein = r->region[i] && r->kind[i] == KIND_VEIN;
		r->region[i] = vein;
		if ( vein )
		{
			r->queue[( *stroke_pixels )++] = i;
		}
	}
	leafimage_thin( r->region, r->w, r->h, r->queue, *stroke_pixels );
	int32_t count = 0;
	for ( int32_t i = 0; i < r->n; ++i )
	{
		r->queue[i] = r->region[i] ? count++ : -1;
	}
	return count;
}

/* Components: each must come within reach of the base dot, unless it is a speck. The roots
 * (each reaching component's pixel nearest the dot) go to v->path; returns their number, or
 * fails naming the nearest miss or a stray stroke. */
static sere_status find_roots( reader* r, veins_work* v, double dot_x, double dot_y, double reach, int32_t* sources )
{
	int32_t neighbors[8];
	for ( int32_t s = 0; s < v->count; ++s )
	{
		v->component[s] = -1;
	}
	int32_t components = 0, stray = -1;
	*sources = 0;
	double nearest_any = INFINITY;
	for ( int32_t s = 0; s < v->count; ++s )
	{
		if ( v->component[s] >= 0 )
		{
			continue;
		}
		int32_t head = 0, tail = 0, nearest = s;
		v->component[s] = components;
		v->order_queue[tail++] = s;
		while ( head < tail )
		{
			int32_t p = v->order_queue[head++];
			if ( pixel_distance( r, v->pixel[p], dot_x, dot_y ) < pixel_distance( r, v->pixel[nearest], dot_x, dot_y ) )
			{
				nearest = p;
			}
			int k = skeleton_neighbors( r, v, p, neighbors );
			for ( int j = 0; j < k; ++j )
			{
				if ( v->component[neighbors[j]] < 0 )
				{
					v->component[neighbors[j]] = components;
					v->order_queue[tail++] = neighbors[j];
				}
			}
		}
		double d = pixel_distance( r, v->pixel[nearest], dot_x, dot_y );
		nearest_any = fmin( nearest_any, d );
		if ( d <= reach )
		{
			v->path[( *sources )++] = nearest; /* the component's root */
		}
		else if ( tail >= DUST_PIXELS && stray < 0 )
		{
			stray = v->pixel[nearest];
		}
		components += 1;
	}
	if ( *sources == 0 )
	{
		return leafimage_fail(
			r, SERE_ERR_GEOMETRY,
			"the veins do not reach the base: the nearest vein pixel is %.0f px from the blue dot (at most "
			"%.0f)",
			nearest_any, reach );
	}
	if ( stray >= 0 )
	{
		return leafimage_fail(
			r, SERE_ERR_GEOMETRY,
			"the vein stroke near pixel (%d, %d) is not connected to the veins that start at the base", stray % r->w,
			stray / r->w );
	}
	return SERE_OK;
}

/* Breadth-first trees from the roots; dist is the path length from the dot's centre. Returns
 * the number of pixels reached, listed in v->order_queue in visiting order. */
static int32_t grow_trees( const reader* r, veins_work* v, int32_t sources, double dot_x, double dot_y )
{
	const int w = r->w;
	int32_t neighbors[8];
	int32_t head = 0, tail = 0;
	for ( int32_t s = 0; s < v->count; ++s )
	{
		v->bfs_parent[s] = -2;
		v->on_vein[s] = -1;
	}
	for ( int32_t k = 0; k < sources; ++k )
	{
		int32_t root = v->path[k];
		v->bfs_parent[root] = -1;
		v->dist[root] = pixel_distance( r, v->pixel[root], dot_x, dot_y );
		v->order_queue[tail++] = root;
	}
	while ( head < tail )
	{
		int32_t p = v->order_queue[head++];
		int k = skeleton_neighbors( r, v, p, neighbors );
		for ( int j = 0; j < k; ++j )
		{
			int32_t q = neighbors[j];
			if ( v->bfs_parent[q] == -2 )
			{
				/* Length along the tree, measured by chords over 8 pixels: pixel steps alone
				 * overstate an oblique stroke by up to 8% and would favour it as the midvein. */
				int32_t a = p;
				for ( int up = 1; up < 8 && v->bfs_parent[a] >= 0; ++up )
				{
					a = v->bfs_parent[a];
				}
				v->bfs_parent[q] = p;
				v->dist[q] = v->dist[a] + hypot( v->pixel[q] % w - v->pixel[a] % w, v->pixel[q] / w - v->pixel[a] / w );
				v->children[p] += 1;
				v->order_queue[tail++] = q;
			}
		}
	}
	return tail;
}

/* The tips of the trees (pixels without children), longest path first; returns their number. */
static int32_t sorted_tips( veins_work* v, int32_t reached )
{
	int32_t tip_count = 0;
	for ( int32_t k = 0; k < reached; ++k )
	{
		int32_t s = v->order_queue[k];
		if ( v->children[s] == 0 )
		{
			v->tips[tip_count++] = ( tip ){ v->dist[s], s };
		}
	}
	qsort( v->tips, (size_t) tip_count, sizeof( tip ), compare_tips );
	return tip_count;
}

/* Splits the trees into veins: each tip in turn walks back until it meets a vein already
 * taken, which is its parent; strokes shorter than spur are dropped. */
static void split_veins( veins_work* v, int32_t tip_count, double spur )
{
	v->vein_count = 0, v->node_count = 0;
	for ( int32_t t = 0; t < tip_count; ++t )
	{
		int32_t length = 0, p = v->tips[t].index;
		while ( p >= 0 && v->on_vein[p] < 0 )
		{
			v->path[length++] = p;
			p = v->bfs_parent[p];
		}
		const int32_t attach = p;
		/* the stroke's own length: from its branch point, or from its tree's root */
		if ( v->tips[t].length - v->dist[attach >= 0 ? attach : v->path[length - 1]] < spur )
		{
			continue; /* a thinning spur, or a speck at the base */
		}
		vein_build* vein = v->veins + v->vein_count;
		vein->first = v->node_count;
		vein->parent = attach >= 0 ? v->on_vein[attach] : -1;
		vein->attach = attach >= 0 ? v->node_pos[attach] : -1;
		vein->order = vein->parent >= 0 ? v->veins[vein->parent].order + 1 : 1;
		v->node_skeleton[v->node_count++] = attach;
		if ( attach >= 0 )
		{
			v->node_keep[v->veins[vein->parent].first + vein->attach] = 1;
		}
		for ( int32_t k = length - 1; k >= 0; --k )
		{
			v->on_vein[v->path[k]] = v->vein_count;
			v->node_pos[v->path[k]] = v->node_count - vein->first;
			v->node_skeleton[v->node_count++] = v->path[k];
		}
		vein->count = v->node_count - vein->first;
		v->vein_count += 1;
	}
}

/* Pixel paths to smoothed, simplified polylines (px). A branch's node 0 takes its parent's
 * final position at the attach node, so it lies exactly on the parent. */
static void vein_polylines( const reader* r, veins_work* v, double base_px, double base_py )
{
	const int w = r->w;
	for ( int32_t k = 0; k < v->node_count; ++k )
	{
		int32_t s = v->node_skeleton[k];
		v->node_xy[2 * k] = s >= 0 ? v->pixel[s] % w + 0.5 : base_px;
		v->node_xy[2 * k + 1] = s >= 0 ? v->pixel[s] / w + 0.5 : base_py;
	}
	for ( int32_t e = 0; e < v->vein_count; ++e )
	{
		const vein_build* vein = v->veins + e;
		double* xy = v->node_xy + 2 * vein->first;
		if ( vein->parent >= 0 )
		{
			const double* on = v->node_xy + 2 * ( v->veins[vein->parent].first + vein->attach );
			xy[0] = on[0], xy[1] = on[1];
		}
		leafimage_smooth( xy, vein->count, 0, v->scratch );
	}
	for ( int32_t e = 0; e < v->vein_count; ++e )
	{
		const vein_build* vein = v->veins + e;
		v->node_keep[vein->first] = v->node_keep[vein->first + vein->count - 1] = 1;
		leafimage_simplify_between_kept( v->node_xy + 2 * vein->first, vein->count, VEIN_TOLERANCE,
										 v->node_keep + vein->first, v->stack );
	}
}

sere_status leafimage_skeleton_veins( reader* r, veins_work* v, double dot_x, double dot_y, double dot_radius,
									  double base_px, double base_py )
{
	int32_t stroke_pixels;
	int32_t count = number_skeleton_pixels( r, &stroke_pixels );
	if ( count == 0 )
	{
		return leafimage_fail( r, SERE_ERR_GEOMETRY, "no veins: the red marks are too small to be strokes" );
	}
	sere_status status = veins_work_create( v, count );
	if ( status != SERE_OK )
	{
		return leafimage_fail( r, status, "out of memory for the vein skeleton" );
	}
	for ( int32_t i = 0; i < r->n; ++i )
	{
		if ( r->queue[i] >= 0 )
		{
			v->pixel[r->queue[i]] = i;
		}
	}
	const double width = (double) stroke_pixels / ( count > 0 ? count : 1 );
	const double reach = dot_radius + 2.0 * width + 4.0, spur = 2.0 * width + 2.0;
	int32_t sources;
	status = find_roots( r, v, dot_x, dot_y, reach, &sources );
	if ( status != SERE_OK )
	{
		return status;
	}
	int32_t reached = grow_trees( r, v, sources, dot_x, dot_y );
	split_veins( v, sorted_tips( v, reached ), spur );
	if ( v->vein_count == 0 )
	{
		return leafimage_fail( r, SERE_ERR_GEOMETRY, "no veins: the red strokes at the base are shorter than %.0f px",
							   spur );
	}
	vein_polylines( r, v, base_px, base_py );
	return SERE_OK;
}

/* The point of segment a-b (a farther than margin inside the outline) where it comes to margin;
 * 0 when that is a itself (then nothing is added). */
static int cut_at_margin( const outline* o, const double* a, const double* b, double margin, double* out )
{
	double lo = 0.0, hi = 1.0;
	for ( int k = 0; k < 50; ++k )
	{
		double mid = 0.5 * ( lo + hi ), p[2] = { a[0] + mid * ( b[0] - a[0] ), a[1] + mid * ( b[1] - a[1] ) };
		if ( sere_point_in_polygon( o->xy, o->count, p[0], p[1] ) &&
			 leafimage_outline_distance( o->xy, o->count, p ) > margin )
		{
			lo = mid;
		}
		else
		{
			hi = mid;
		}
	}
	out[0] = a[0] + lo * ( b[0] - a[0] );
	out[1] = a[1] + lo * ( b[1] - a[1] );
	return out[0] != a[0] || out[1] != a[1];
}

/* Leaf-coordinate veins kept strictly inside the outline: each is cut where it first comes within
 * margin of it (a vein from the base first has to leave the margin band it starts in; points in
 * that band stay if they are inside by more than a quarter pixel). Veins that keep under two
 * points, get shorter than two pixels, or whose branch point was cut away are dropped with
 * their branches. Fills leaf's vein arrays. */
sere_status leafimage_place_veins( reader* r, veins_work* v, const outline* o, sere_leaf_file* leaf )
{
	const double margin = fmax( MARGIN_FRACTION, MARGIN_MIN_PIXELS / o->scale );
	const double quarter = 0.25 / o->scale, shortest = 2.0 / o->scale;
	leaf->veins = malloc( sizeof( sere_vein ) * (size_t) v->vein_count );
	leaf->vein_xy = malloc( sizeof( double ) * 2 * ( (size_t) v->node_count + (size_t) v->vein_count ) );
	int32_t* final_index = malloc( sizeof( int32_t ) * (size_t) v->vein_count );
	if ( leaf->veins == NULL || leaf->vein_xy == NULL || final_index == NULL )
	{
		free( final_index );
		return leafimage_fail( r, SERE_ERR_MEMORY, "out of memory for the veins" );
	}
	int32_t points = 0, kept_veins = 0;
	for ( int32_t e = 0; e < v->vein_count; ++e )
	{
		const vein_build* vein = v->veins + e;
		final_index[e] = -1;
		for ( int32_t k = 0; k < vein->count; ++k )
		{
			v->node_final[vein->first + k] = -1;
		}
		int32_t parent = vein->parent >= 0 ? final_index[vein->parent] : -1;
		if ( vein->parent >= 0 && ( parent < 0 || v->node_final[v->veins[vein->parent].first + vein->attach] < 0 ) )
		{
			continue;
		}
		double* out = leaf->vein_xy + 2 * points;
		int32_t m = 0;
		if ( vein->parent >= 0 )
		{
			const double* on = leaf->vein_xy + 2 * v->node_final[v->veins[vein->parent].first + vein->attach];
			out[0] = on[0], out[1] = on[1];
		}
		else
		{
			out[0] = 0.0, out[1] = 0.0;
		}
		v->node_final[vein->first] = points;
		m = 1;
		int leaving = vein->parent < 0; /* still in the margin band around the base */
		int cut = 0;
		double previous[2] = { out[0], out[1] };
		for ( int32_t k = 1; k < vein->count && !cut; ++k )
		{
			if ( !v->node_keep[vein->first + k] )
			{
				continue;
			}
			const double* px = v->node_xy + 2 * ( vein->first + k );
			double p[2] = { ( px[0] - o->base_px ) / o->scale, ( o->base_py - px[1] ) / o->scale };
			int inside = sere_point_in_polygon( o->xy, o->count, p[0], p[1] );
			double d = leafimage_outline_distance( o->xy, o->count, p );
			if ( leaving && d <= margin )
			{
				if ( inside && d > quarter )
				{
					out[2 * m] = p[0], out[2 * m + 1] = p[1];
					v->node_final[vein->first + k] = points + m;
					m += 1;
				}
				previous[0] = p[0], previous[1] = p[1];
				continue;
			}
			if ( inside && d > margin )
			{
				leaving = 0;
				out[2 * m] = p[0], out[2 * m + 1] = p[1];
				v->node_final[vein->first + k] = points + m;
				m += 1;
			}
			else
			{
				cut = 1;
				if ( !leaving && ( m > 1 || ( sere_point_in_polygon( o->xy, o->count, previous[0], previous[1] ) &&
											  leafimage_outline_distance( o->xy, o->count, previous ) > margin ) ) )
				{
					m += cut_at_margin( o, previous, p, margin, out + 2 * m );
				}
			}
			previous[0] = p[0], previous[1] = p[1];
		}
		double length = 0.0;
		for ( int32_t k = 1; k < m; ++k )
		{
			length += hypot( out[2 * k] - out[2 * k - 2], out[2 * k + 1] - out[2 * k - 1] );
		}
		if ( m < 2 || length < shortest || leaving )
		{
			for ( int32_t k = 0; k < vein->count; ++k )
			{
				v->node_final[vein->first + k] = -1;
			}
			continue;
		}
		final_index[e] = kept_veins;
		leaf->veins[kept_veins++] = ( sere_vein ){ points, m, vein->order, parent };
		points += m;
	}
	free( final_index );
	if ( kept_veins == 0 )
	{
		return leafimage_fail( r, SERE_ERR_GEOMETRY, "no veins left: every vein runs within %.0f px of the outline",
							   margin * o->scale );
	}
	leaf->shape.vein_count = kept_veins;
	leaf->shape.veins = leaf->veins;
	leaf->shape.vein_point_count = points;
	leaf->shape.vein_xy = leaf->vein_xy;
	return SERE_OK;
}

/* The largest 8-connected blue blob: its centre and radius (from its area), px. */
