#include "leafimage.h"

#include <math.h>
#include <png.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum
{
	PIXEL_BACKGROUND = 0,
	PIXEL_BLADE = 1,
	PIXEL_VEIN = 2,
	PIXEL_BASE = 3,
};

typedef struct image
{
	int w, h;
	uint8_t* kind;
} image;

static sere_status fail( char* err, size_t err_size, const char* path, const char* what, sere_status status )
{
	snprintf( err, err_size, "%s: %s", path, what );
	return status;
}

static sere_status load( const char* path, image* img, char* err, size_t err_size )
{
	png_image png;
	memset( &png, 0, sizeof( png ) );
	png.version = PNG_IMAGE_VERSION;
	if ( !png_image_begin_read_from_file( &png, path ) )
	{
		char what[256];
		snprintf( what, sizeof( what ), "not a readable PNG (%s)", png.message );
		return fail( err, err_size, path, what, SERE_ERR_ARGUMENT );
	}
	if ( png.width > 8192 || png.height > 8192 || png.width < 8 || png.height < 8 )
	{
		png_image_free( &png );
		return fail( err, err_size, path, "image must be 8 to 8192 pixels on each side", SERE_ERR_ARGUMENT );
	}
	png.format = PNG_FORMAT_RGBA;
	uint8_t* rgba = malloc( PNG_IMAGE_SIZE( png ) );
	if ( rgba == NULL || !png_image_finish_read( &png, NULL, rgba, 0, NULL ) )
	{
		free( rgba );
		png_image_free( &png );
		return fail( err, err_size, path, "cannot decode the PNG", SERE_ERR_ARGUMENT );
	}
	img->w = (int) png.width;
	img->h = (int) png.height;
	img->kind = calloc( (size_t) img->w * img->h, 1 );
	if ( img->kind == NULL )
	{
		free( rgba );
		return fail( err, err_size, path, "out of memory", SERE_ERR_MEMORY );
	}
	for ( int i = 0; i < img->w * img->h; ++i )
	{
		const uint8_t* p = rgba + 4 * i;
		uint8_t k = PIXEL_BLADE;
		if ( p[3] < 128 || ( p[0] > 230 && p[1] > 230 && p[2] > 230 ) )
			k = PIXEL_BACKGROUND;
		else if ( p[0] > 180 && p[1] < 90 && p[2] < 90 )
			k = PIXEL_VEIN;
		else if ( p[2] > 180 && p[0] < 90 && p[1] < 90 )
			k = PIXEL_BASE;
		img->kind[i] = k;
	}
	free( rgba );
	return SERE_OK;
}

/* Keeps the largest 4-connected non-background region and fills its holes. */
static int keep_largest( image* img )
{
	int n = img->w * img->h;
	int32_t* label = malloc( sizeof( int32_t ) * n );
	int32_t* queue = malloc( sizeof( int32_t ) * n );
	if ( label == NULL || queue == NULL )
	{
		free( label ), free( queue );
		return -1;
	}
	for ( int i = 0; i < n; ++i )
		label[i] = -1;
	int best = -1, best_size = 0, next = 0;
	const int dx[4] = { 1, -1, 0, 0 }, dy[4] = { 0, 0, 1, -1 };
	for ( int s = 0; s < n; ++s )
	{
		if ( img->kind[s] == PIXEL_BACKGROUND || label[s] >= 0 )
			continue;
		int head = 0, tail = 0;
		queue[tail++] = s;
		label[s] = next;
		while ( head < tail )
		{
			int p = queue[head++], x = p % img->w, y = p / img->w;
			for ( int k = 0; k < 4; ++k )
			{
				int qx = x + dx[k], qy = y + dy[k];
				if ( qx < 0 || qy < 0 || qx >= img->w || qy >= img->h )
					continue;
				int q = qy * img->w + qx;
				if ( img->kind[q] != PIXEL_BACKGROUND && label[q] < 0 )
				{
					label[q] = next;
					queue[tail++] = q;
				}
			}
		}
		if ( tail > best_size )
			best_size = tail, best = next;
		next += 1;
	}
	/* Background reachable from the border stays background; everything else is blade. */
	uint8_t* outside = calloc( (size_t) n, 1 );
	int head = 0, tail = 0;
	for ( int i = 0; i < n; ++i )
	{
		int x = i % img->w, y = i / img->w;
		int border = x == 0 || y == 0 || x == img->w - 1 || y == img->h - 1;
		if ( border && label[i] != best )
		{
			outside[i] = 1;
			queue[tail++] = i;
		}
	}
	while ( head < tail )
	{
		int p = queue[head++], x = p % img->w, y = p / img->w;
		for ( int k = 0; k < 4; ++k )
		{
			int qx = x + dx[k], qy = y + dy[k];
			if ( qx < 0 || qy < 0 || qx >= img->w || qy >= img->h )
				continue;
			int q = qy * img->w + qx;
			if ( !outside[q] && label[q] != best )
			{
				outside[q] = 1;
				queue[tail++] = q;
			}
		}
	}
	for ( int i = 0; i < n; ++i )
	{
		if ( outside[i] )
			img->kind[i] = PIXEL_BACKGROUND;
		else if ( img->kind[i] == PIXEL_BACKGROUND )
			img->kind[i] = PIXEL_BLADE;
	}
	free( outside ), free( label ), free( queue );
	return best_size;
}

static int inside_px( const image* img, int x, int y )
{
	return x >= 0 && y >= 0 && x < img->w && y < img->h && img->kind[y * img->w + x] != PIXEL_BACKGROUND;
}

/* Traces the region's border along pixel edges (a square-tracing walk on the corner grid,
 * keeping the region on the left), giving the corners of the boundary as a closed loop. */
static int trace( const image* img, double** out )
{
	int sx = -1, sy = -1;
	for ( int y = 0; y < img->h && sx < 0; ++y )
		for ( int x = 0; x < img->w; ++x )
			if ( inside_px( img, x, y ) )
			{
				sx = x, sy = y;
				break;
			}
	if ( sx < 0 )
		return 0;
	/* Corner (cx, cy) is the top-left corner of pixel (cx, cy). Start at the top edge of the
	 * first pixel, walking +x: the region is below (on the right in image coordinates, which
	 * is on the left once y is flipped up). */
	int capacity = 4096, count = 0;
	double* pts = malloc( sizeof( double ) * 2 * capacity );
	int cx = sx, cy = sy, dir = 0; /* 0:+x 1:+y 2:-x 3:-y in image coordinates */
	const int mx[4] = { 1, 0, -1, 0 }, my[4] = { 0, 1, 0, -1 };
	do
	{
		if ( count == capacity )
		{
			capacity *= 2;
			pts = realloc( pts, sizeof( double ) * 2 * capacity );
		}
		pts[2 * count] = cx;
		pts[2 * count + 1] = cy;
		count += 1;
		cx += mx[dir], cy += my[dir];
		/* At the new corner, the pixels ahead-left and ahead-right of the walking direction
		 * decide the turn (region kept on the walker's right in image coordinates). */
		int turned = 0;
		for ( int attempt = 0; attempt < 4 && !turned; ++attempt )
		{
			int d = ( dir + 3 + attempt ) % 4; /* try left first, then straight, right, back */
			int lx, ly, rx, ry;				   /* pixels on the left and right of the edge leaving along d */
			switch ( d )
			{
				case 0:
					lx = cx, ly = cy - 1, rx = cx, ry = cy;
					break;
				case 1:
					lx = cx, ly = cy, rx = cx - 1, ry = cy;
					break;
				case 2:
					lx = cx - 1, ly = cy, rx = cx - 1, ry = cy - 1;
					break;
				default:
					lx = cx - 1, ly = cy - 1, rx = cx, ry = cy - 1;
					break;
			}
			if ( inside_px( img, rx, ry ) && !inside_px( img, lx, ly ) )
			{
				dir = d;
				turned = 1;
			}
		}
		if ( !turned || count > 8 * ( img->w + img->h ) * 8 )
		{
			free( pts );
			return -1;
		}
	} while ( cx != sx || cy != sy || dir != 0 );
	*out = pts;
	return count;
}

/* Douglas–Peucker on a closed loop (split at point 0 and the farthest point from it). */
static void simplify( const double* p, int a, int b, double eps, uint8_t* keep )
{
	double ax = p[2 * a], ay = p[2 * a + 1], bx = p[2 * b], by = p[2 * b + 1];
	double ex = bx - ax, ey = by - ay, len = hypot( ex, ey );
	double worst = -1.0;
	int at = -1;
	for ( int i = a + 1; i < b; ++i )
	{
		double d = len > 0 ? fabs( ( p[2 * i] - ax ) * ey - ( p[2 * i + 1] - ay ) * ex ) / len
						   : hypot( p[2 * i] - ax, p[2 * i + 1] - ay );
		if ( d > worst )
			worst = d, at = i;
	}
	if ( at >= 0 && worst > eps )
	{
		keep[at] = 1;
		simplify( p, a, at, eps, keep );
		simplify( p, at, b, eps, keep );
	}
}

/* Zhang–Suen thinning of the vein pixels to one-pixel-wide skeletons. */
static void thin( uint8_t* m, int w, int h )
{
	uint8_t* mark = calloc( (size_t) w * h, 1 );
	int changed = 1;
	while ( changed )
	{
		changed = 0;
		for ( int pass = 0; pass < 2; ++pass )
		{
			memset( mark, 0, (size_t) w * h );
			for ( int y = 1; y < h - 1; ++y )
				for ( int x = 1; x < w - 1; ++x )
				{
					if ( !m[y * w + x] )
						continue;
					int p[9] = { m[( y - 1 ) * w + x],	   m[( y - 1 ) * w + x + 1], m[y * w + x + 1],
								 m[( y + 1 ) * w + x + 1], m[( y + 1 ) * w + x],	 m[( y + 1 ) * w + x - 1],
								 m[y * w + x - 1],		   m[( y - 1 ) * w + x - 1], m[( y - 1 ) * w + x] };
					int b = 0, a = 0;
					for ( int k = 0; k < 8; ++k )
					{
						b += p[k] != 0;
						a += !p[k] && p[k + 1];
					}
					int c = pass == 0 ? !( p[0] && p[2] && p[4] ) : !( p[0] && p[2] && p[6] );
					int d = pass == 0 ? !( p[2] && p[4] && p[6] ) : !( p[0] && p[4] && p[6] );
					if ( b >= 2 && b <= 6 && a == 1 && c && d )
						mark[y * w + x] = 1;
				}
			for ( int i = 0; i < w * h; ++i )
				if ( mark[i] )
				{
					m[i] = 0;
					changed = 1;
				}
		}
	}
	free( mark );
}

typedef struct vein_path
{
	int32_t* px; /* pixel indices, from the branch point to the tip */
	int32_t count;
	int32_t parent;
} vein_path;

sere_status sere_leaf_from_png( const char* path, sere_leaf_file* leaf, char* err, size_t err_size )
{
	memset( leaf, 0, sizeof( *leaf ) );
	image img = { 0 };
	sere_status status = load( path, &img, err, err_size );
	if ( status != SERE_OK )
		return status;
	const int w = img.w, h = img.h, n = w * h;
	if ( keep_largest( &img ) < 64 )
	{
		free( img.kind );
		return fail( err, err_size, path, "no leaf: no blade pixels (everything is white or transparent)",
					 SERE_ERR_GEOMETRY );
	}
	/* base: the centroid of the blue pixels */
	double bx = 0, by = 0;
	int blue = 0, veins = 0, x0 = w, x1 = 0, y0 = h, y1 = 0;
	for ( int i = 0; i < n; ++i )
	{
		int x = i % w, y = i / w;
		if ( img.kind[i] == PIXEL_BASE )
			bx += x + 0.5, by += y + 0.5, blue += 1;
		veins += img.kind[i] == PIXEL_VEIN;
		if ( img.kind[i] != PIXEL_BACKGROUND )
			x0 = x < x0 ? x : x0, x1 = x > x1 ? x : x1, y0 = y < y0 ? y : y0, y1 = y > y1 ? y : y1;
	}
	if ( blue == 0 )
	{
		free( img.kind );
		return fail( err, err_size, path, "no base: draw a blue dot (B > 180, R and G < 90) at the petiole",
					 SERE_ERR_GEOMETRY );
	}
	if ( veins == 0 )
	{
		free( img.kind );
		return fail( err, err_size, path, "no veins: draw them in red (R > 180, G and B < 90)", SERE_ERR_GEOMETRY );
	}
	bx /= blue, by /= blue;
	double* corners = NULL;
	int corner_count = trace( &img, &corners );
	if ( corner_count < 8 )
	{
		free( img.kind ), free( corners );
		return fail( err, err_size, path, "cannot trace the silhouette", SERE_ERR_GEOMETRY );
	}
	uint8_t* keep = calloc( (size_t) corner_count + 1, 1 );
	double* loop = malloc( sizeof( double ) * 2 * ( corner_count + 1 ) );
	memcpy( loop, corners, sizeof( double ) * 2 * corner_count );
	loop[2 * corner_count] = loop[0], loop[2 * corner_count + 1] = loop[1];
	keep[0] = keep[corner_count] = 1;
	/* 0.4 px: every blade pixel centre stays inside the simplified polygon */
	int far = 0;
	for ( int i = 1; i < corner_count; ++i )
		if ( hypot( loop[2 * i] - loop[0], loop[2 * i + 1] - loop[1] ) >
			 hypot( loop[2 * far] - loop[0], loop[2 * far + 1] - loop[1] ) )
			far = i;
	keep[far] = 1;
	simplify( loop, 0, far, 0.4, keep );
	simplify( loop, far, corner_count, 0.4, keep );
	const double scale = 1.0 / fmax( 1.0, (double) ( ( y1 - y0 ) > ( x1 - x0 ) ? ( y1 - y0 ) : ( x1 - x0 ) ) + 1.0 );
	/* The base snaps to the nearest outline corner, which becomes outline point 0. */
	int base_corner = 0;
	for ( int i = 0; i < corner_count; ++i )
		if ( keep[i] && hypot( loop[2 * i] - bx, loop[2 * i + 1] - by ) <
							hypot( loop[2 * base_corner] - bx, loop[2 * base_corner + 1] - by ) )
			base_corner = i;
	keep[base_corner] = 1;
	int kept = 0;
	for ( int i = 0; i < corner_count; ++i )
		kept += keep[i];
	leaf->outline_xy = malloc( sizeof( double ) * 2 * kept );
	leaf->outline_line = calloc( (size_t) kept, sizeof( int32_t ) );
	const double ox = loop[2 * base_corner], oy = loop[2 * base_corner + 1];
	int k = 0;
	for ( int s = 0; s < corner_count; ++s )
	{
		int i = ( base_corner + s ) % corner_count;
		if ( keep[i] )
		{
			leaf->outline_xy[2 * k] = ( loop[2 * i] - ox ) * scale;
			leaf->outline_xy[2 * k + 1] = ( oy - loop[2 * i + 1] ) * scale;
			k += 1;
		}
	}
	free( keep ), free( corners );
	/* Make the traced loop counter-clockwise in leaf coordinates, keeping the base first. */
	double twice_area = 0.0;
	for ( int i = 0, j = kept - 1; i < kept; j = i++ )
		twice_area += leaf->outline_xy[2 * j] * leaf->outline_xy[2 * i + 1] -
					  leaf->outline_xy[2 * i] * leaf->outline_xy[2 * j + 1];
	for ( int i = 1, j = kept - 1; twice_area < 0.0 && i < j; ++i, --j )
	{
		double tx = leaf->outline_xy[2 * i], ty = leaf->outline_xy[2 * i + 1];
		leaf->outline_xy[2 * i] = leaf->outline_xy[2 * j], leaf->outline_xy[2 * i + 1] = leaf->outline_xy[2 * j + 1];
		leaf->outline_xy[2 * j] = tx, leaf->outline_xy[2 * j + 1] = ty;
	}

	/* Veins: thin, then follow the skeleton from the pixel nearest the base. */
	uint8_t* skel = calloc( (size_t) n, 1 );
	for ( int i = 0; i < n; ++i )
		skel[i] = img.kind[i] == PIXEL_VEIN;
	thin( skel, w, h );
	int root = -1;
	double root_d = INFINITY;
	for ( int i = 0; i < n; ++i )
		if ( skel[i] )
		{
			double d = hypot( i % w + 0.5 - ox, i / w + 0.5 - oy );
			if ( d < root_d )
				root_d = d, root = i;
		}
	int32_t* parent = malloc( sizeof( int32_t ) * n );
	int32_t* depth = malloc( sizeof( int32_t ) * n );
	int32_t* queue = malloc( sizeof( int32_t ) * n );
	int32_t* children = calloc( (size_t) n, sizeof( int32_t ) );
	for ( int i = 0; i < n; ++i )
		parent[i] = -2, depth[i] = -1;
	int head = 0, tail = 0;
	queue[tail++] = root;
	parent[root] = -1, depth[root] = 0;
	while ( head < tail )
	{
		int p = queue[head++], x = p % w, y = p / w;
		for ( int dy = -1; dy <= 1; ++dy )
			for ( int dx = -1; dx <= 1; ++dx )
			{
				int qx = x + dx, qy = y + dy;
				if ( ( dx || dy ) && qx >= 0 && qy >= 0 && qx < w && qy < h && skel[qy * w + qx] &&
					 depth[qy * w + qx] < 0 )
				{
					int q = qy * w + qx;
					depth[q] = depth[p] + 1, parent[q] = p, children[p] += 1;
					queue[tail++] = q;
				}
			}
	}
	int unreached = 0;
	for ( int i = 0; i < n; ++i )
		unreached += skel[i] && depth[i] < 0;
	status = SERE_OK;
	if ( unreached > 3 )
	{
		status = fail( err, err_size, path, "a vein stroke does not touch the vein network that starts at the base",
					   SERE_ERR_GEOMETRY );
	}
	/* Endpoints in BFS order (by depth); walked from the deepest, the midvein's tip, down. */
	int32_t* tips = malloc( sizeof( int32_t ) * n );
	int tip_count = 0;
	for ( int i = 0; i < tail; ++i )
		if ( children[queue[i]] == 0 )
			tips[tip_count++] = queue[i];
	int32_t* on_vein = malloc( sizeof( int32_t ) * n );
	for ( int i = 0; i < n; ++i )
		on_vein[i] = -1;
	vein_path* paths = calloc( (size_t) tip_count + 1, sizeof( vein_path ) );
	uint8_t* branch = calloc( (size_t) n, 1 );
	int path_count = 0;
	for ( int t = tip_count - 1; t >= 0 && status == SERE_OK; --t )
	{
		int length = 0, p = tips[t];
		while ( p >= 0 && on_vein[p] < 0 )
			length += 1, p = parent[p];
		int attach = p; /* -1: reached the root without meeting a vein (the midvein) */
		if ( attach >= 0 && length < 6 )
			continue; /* a thinning spur */
		vein_path* v = paths + path_count;
		v->count = length + ( attach >= 0 ? 1 : 0 );
		v->px = malloc( sizeof( int32_t ) * v->count );
		v->parent = attach >= 0 ? on_vein[attach] : -1;
		int q = tips[t];
		for ( int m = v->count - 1; m >= 0; --m )
		{
			v->px[m] = q;
			q = m > 0 ? parent[q] : q;
		}
		if ( attach >= 0 )
		{
			v->px[0] = attach;
			branch[attach] = 1;
		}
		for ( int m = attach >= 0 ? 1 : 0; m < v->count; ++m )
			on_vein[v->px[m]] = path_count;
		path_count += 1;
	}
	/* Polylines: every 4th pixel, branch pixels and the tip, in leaf coordinates; the midvein
	 * starts at the base. Tips closer than 3 px to the margin are cut back. */
	leaf->veins = calloc( (size_t) path_count + 1, sizeof( sere_vein ) );
	leaf->vein_xy = malloc( sizeof( double ) * 2 * ( n > 0 ? (size_t) tail + 2 * path_count + 2 : 2 ) );
	leaf->vein_line = calloc( (size_t) tail + 2 * path_count + 2, sizeof( int32_t ) );
	int points = 0, vein_count = 0;
	for ( int v = 0; v < path_count && status == SERE_OK; ++v )
	{
		vein_path* pv = paths + v;
		int first = points;
		if ( pv->parent < 0 )
		{
			leaf->vein_xy[2 * points] = 0.0, leaf->vein_xy[2 * points + 1] = 0.0;
			points += 1;
		}
		int end = pv->count;
		while ( end > 1 && !branch[pv->px[end - 1]] )
		{
			double px = pv->px[end - 1] % w + 0.5, py = pv->px[end - 1] / w + 0.5;
			int near = 0;
			for ( int r = -3; r <= 3 && !near; ++r )
				for ( int c = -3; c <= 3 && !near; ++c )
					near = !inside_px( &img, (int) px + c, (int) py + r );
			if ( !near )
				break;
			end -= 1;
		}
		for ( int m = 0; m < end; ++m )
		{
			if ( m == 0 || m == end - 1 || m % 4 == 0 || branch[pv->px[m]] )
			{
				leaf->vein_xy[2 * points] = ( pv->px[m] % w + 0.5 - ox ) * scale;
				leaf->vein_xy[2 * points + 1] = ( oy - ( pv->px[m] / w + 0.5 ) ) * scale;
				points += 1;
			}
		}
		int order = pv->parent < 0 ? 1 : leaf->veins[pv->parent].order + 1;
		leaf->veins[vein_count++] = ( sere_vein ){ first, points - first, order, pv->parent };
	}
	for ( int v = 0; v < path_count; ++v )
		free( paths[v].px );
	free( paths ), free( branch ), free( on_vein ), free( tips ), free( parent ), free( depth ), free( queue );
	free( children ), free( skel ), free( img.kind ), free( loop );
	if ( status != SERE_OK )
	{
		sere_leaf_file_free( leaf );
		return status;
	}
	const char* slash = strrchr( path, '/' );
	snprintf( leaf->name, sizeof( leaf->name ), "%s", slash ? slash + 1 : path );
	leaf->shape =
		( sere_leaf_shape ){ 0.0, 0.0, kept, leaf->outline_xy, vein_count, leaf->veins, points, leaf->vein_xy };
	sere_shape_check check;
	status = sere_shape_validate( &leaf->shape, &check );
	if ( status != SERE_OK )
	{
		char what[256];
		snprintf( what, sizeof( what ), "traced leaf is not usable: %s", sere_shape_problem_text( check.problem ) );
		sere_leaf_file_free( leaf );
		return fail( err, err_size, path, what, status );
	}
	return SERE_OK;
}
