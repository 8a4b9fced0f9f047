#include "leafimage.h"

#include <errno.h>
#include <math.h>
#include <png.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MAX_SIDE		 8192
#define MIN_BLADE_PIXELS 64
/* Douglas-Peucker tolerances, px. A chord cuts about 2/3 of its sag off a convex rim, so 0.25 px
 * keeps the outline's area within 0.2%; veins only need their course. */
#define OUTLINE_TOLERANCE 0.25
#define VEIN_TOLERANCE	  0.5
/* Taubin lambda|mu passes: enough to remove the staircase of an unantialiased rim. */
#define SMOOTH_PASSES 8
/* Veins stop this fraction of the leaf length (and at least this many pixels) inside the outline. */
#define MARGIN_FRACTION	  0.01
#define MARGIN_MIN_PIXELS 2.0
/* Skeleton pieces smaller than this are specks, not strokes. */
#define DUST_PIXELS 4

enum
{
	KIND_BACKGROUND,
	KIND_BLADE,
	KIND_VEIN,
	KIND_BASE,
};

typedef struct png_failure
{
	jmp_buf jump;
	char message[200];
} png_failure;

/* Everything one read needs; the per-pixel arrays are n = width x height long. */
typedef struct reader
{
	const char* path;
	char* err;
	size_t err_size;
	int w, h;
	int32_t n;
	uint8_t* kind;
	uint8_t* ink;	  /* how far from white (and how opaque) a pixel is, 0..255 */
	uint8_t* ink_max; /* the largest ink in the 5 x 5 window (full coverage nearby); then the dot mask */
	uint8_t* region;  /* the leaf silhouette; then the vein strokes, thinned to their skeleton */
	int32_t* queue;	  /* flood fills; then the pixels being thinned; then pixel -> skeleton index */
	/* libpng state lives here, not in locals, so nothing is clobbered by its longjmp */
	png_failure failure;
	FILE* file;
	png_structp png;
	png_infop info;
	uint8_t* rgba;
	png_bytep* rows;
} reader;

static sere_status fail( reader* r, sere_status status, const char* format, ... )
	__attribute__( ( format( printf, 3, 4 ) ) );

/* One line "PATH: problem" into the caller's buffer. */
static sere_status fail( reader* r, sere_status status, const char* format, ... )
{
	char what[512];
	va_list args;
	va_start( args, format );
	vsnprintf( what, sizeof( what ), format, args );
	va_end( args );
	if ( r->err != NULL && r->err_size > 0 )
	{
		snprintf( r->err, r->err_size, "%s: %s", r->path, what );
	}
	return status;
}

static void png_on_error( png_structp png, png_const_charp message )
{
	png_failure* failure = png_get_error_ptr( png );
	snprintf( failure->message, sizeof( failure->message ), "%s", message );
	longjmp( failure->jump, 1 );
}

static void png_on_warning( png_structp png, png_const_charp message )
{
	(void) png;
	(void) message;
}

static void png_close( reader* r )
{
	png_destroy_read_struct( &r->png, &r->info, NULL );
	fclose( r->file );
	r->file = NULL;
	free( r->rows );
	r->rows = NULL;
}

/* Any PNG (palette, gray, 1-16 bits, with or without alpha or tRNS, interlaced) as 8-bit RGBA. */
static sere_status load_png( reader* r )
{
	r->file = fopen( r->path, "rb" );
	if ( r->file == NULL )
	{
		return fail( r, SERE_ERR_ARGUMENT, "cannot open: %s", strerror( errno ) );
	}
	png_byte signature[8];
	if ( fread( signature, 1, sizeof( signature ), r->file ) != sizeof( signature ) ||
		 png_sig_cmp( signature, 0, sizeof( signature ) ) != 0 )
	{
		fclose( r->file );
		r->file = NULL;
		return fail( r, SERE_ERR_ARGUMENT, "not a PNG file" );
	}
	r->png = png_create_read_struct( PNG_LIBPNG_VER_STRING, &r->failure, png_on_error, png_on_warning );
	r->info = r->png != NULL ? png_create_info_struct( r->png ) : NULL;
	if ( r->info == NULL )
	{
		png_close( r );
		return fail( r, SERE_ERR_MEMORY, "out of memory" );
	}
	if ( setjmp( r->failure.jump ) )
	{
		png_close( r );
		free( r->rgba );
		r->rgba = NULL;
		return fail( r, SERE_ERR_ARGUMENT, "corrupt PNG: %s", r->failure.message );
	}
	png_init_io( r->png, r->file );
	png_set_sig_bytes( r->png, sizeof( signature ) );
	png_read_info( r->png, r->info );
	png_uint_32 width = png_get_image_width( r->png, r->info ), height = png_get_image_height( r->png, r->info );
	if ( width > MAX_SIDE || height > MAX_SIDE )
	{
		png_close( r );
		return fail( r, SERE_ERR_ARGUMENT, "image too large: %lu x %lu pixels (at most %d x %d)", (unsigned long) width,
					 (unsigned long) height, MAX_SIDE, MAX_SIDE );
	}
	int color = png_get_color_type( r->png, r->info );
	png_set_expand( r->png ); /* palette -> RGB, gray below 8 bits -> 8 bits, tRNS -> alpha */
	png_set_strip_16( r->png );
	if ( color == PNG_COLOR_TYPE_GRAY || color == PNG_COLOR_TYPE_GRAY_ALPHA )
	{
		png_set_gray_to_rgb( r->png );
	}
	if ( ( color & PNG_COLOR_MASK_ALPHA ) == 0 && !png_get_valid( r->png, r->info, PNG_INFO_tRNS ) )
	{
		png_set_add_alpha( r->png, 0xff, PNG_FILLER_AFTER );
	}
	png_set_interlace_handling( r->png );
	png_read_update_info( r->png, r->info );
	if ( png_get_rowbytes( r->png, r->info ) != 4 * (size_t) width )
	{
		png_close( r );
		return fail( r, SERE_ERR_ARGUMENT, "unsupported PNG layout" );
	}
	r->rgba = malloc( 4 * (size_t) width * height );
	r->rows = malloc( sizeof( png_bytep ) * height );
	if ( r->rgba == NULL || r->rows == NULL )
	{
		png_close( r );
		free( r->rgba );
		r->rgba = NULL;
		return fail( r, SERE_ERR_MEMORY, "out of memory for a %lu x %lu image", (unsigned long) width,
					 (unsigned long) height );
	}
	for ( png_uint_32 y = 0; y < height; ++y )
	{
		r->rows[y] = r->rgba + 4 * (size_t) width * y;
	}
	png_read_image( r->png, r->rows );
	png_read_end( r->png, NULL );
	png_close( r );
	r->w = (int) width;
	r->h = (int) height;
	r->n = (int32_t) width * (int32_t) height;
	return SERE_OK;
}

/* The color convention of leafimage.h, and each pixel's ink: max(255 - R, 255 - G, 255 - B)
 * scaled by alpha, which is linear in the coverage of an antialiased rim over white or over
 * transparency, so ink / ink_max estimates how much of a pixel the blade covers. */
static void classify( reader* r )
{
	for ( int32_t i = 0; i < r->n; ++i )
	{
		const uint8_t* p = r->rgba + 4 * (size_t) i;
		int red = p[0], green = p[1], blue = p[2], alpha = p[3];
		int low = red < green ? red : green;
		low = blue < low ? blue : low;
		r->ink[i] = (uint8_t) ( ( ( 255 - low ) * alpha + 127 ) / 255 );
		uint8_t kind = KIND_BLADE;
		if ( alpha < 128 || ( red > 230 && green > 230 && blue > 230 ) )
		{
			kind = KIND_BACKGROUND;
		}
		else if ( red > 200 && green < 80 && blue < 80 )
		{
			kind = KIND_VEIN;
		}
		else if ( blue > 200 && red < 80 && green < 80 )
		{
			kind = KIND_BASE;
		}
		r->kind[i] = kind;
	}
}

/* 5 x 5 running maximum, separably; scratch is n bytes. */
static void max_filter( const uint8_t* in, uint8_t* scratch, uint8_t* out, int w, int h )
{
	for ( int y = 0; y < h; ++y )
	{
		for ( int x = 0; x < w; ++x )
		{
			uint8_t m = 0;
			for ( int k = x - 2; k <= x + 2; ++k )
			{
				if ( k >= 0 && k < w && in[y * w + k] > m )
				{
					m = in[y * w + k];
				}
			}
			scratch[y * w + x] = m;
		}
	}
	for ( int y = 0; y < h; ++y )
	{
		for ( int x = 0; x < w; ++x )
		{
			uint8_t m = 0;
			for ( int k = y - 2; k <= y + 2; ++k )
			{
				if ( k >= 0 && k < h && scratch[k * w + x] > m )
				{
					m = scratch[k * w + x];
				}
			}
			out[y * w + x] = m;
		}
	}
}

/* Floods the 4-connected pixels equal to from, starting at seed, setting them to to. */
static int32_t flood4( uint8_t* m, int w, int h, int32_t seed, uint8_t from, uint8_t to, int32_t* queue )
{
	int32_t head = 0, tail = 0;
	m[seed] = to;
	queue[tail++] = seed;
	while ( head < tail )
	{
		int32_t p = queue[head++];
		int x = p % w, y = p / w;
		int32_t next[4] = { x > 0 ? p - 1 : -1, x + 1 < w ? p + 1 : -1, y > 0 ? p - w : -1, y + 1 < h ? p + w : -1 };
		for ( int k = 0; k < 4; ++k )
		{
			if ( next[k] >= 0 && m[next[k]] == from )
			{
				m[next[k]] = to;
				queue[tail++] = next[k];
			}
		}
	}
	return tail;
}

/* The silhouette: blade pixels, minus rim pixels less than half covered (so the region's edge
 * is the 50% coverage line), then the largest 4-connected piece with its holes filled. Holes
 * are found by flooding the background 4-connected from the border, so a pocket reached only
 * diagonally is filled too: the region then has no diagonal-only contacts (no marching-squares
 * saddles) and its boundary is one simple loop. Returns the region's pixel count. */
static int32_t silhouette( reader* r )
{
	const int w = r->w, h = r->h;
	max_filter( r->ink, r->region, r->ink_max, w, h );
	for ( int y = 0; y < h; ++y )
	{
		for ( int x = 0; x < w; ++x )
		{
			int32_t i = y * w + x;
			int rim = 0;
			for ( int dy = -1; dy <= 1 && !rim; ++dy )
			{
				for ( int dx = -1; dx <= 1 && !rim; ++dx )
				{
					int qx = x + dx, qy = y + dy;
					rim = qx < 0 || qy < 0 || qx >= w || qy >= h || r->kind[qy * w + qx] == KIND_BACKGROUND;
				}
			}
			r->region[i] = r->kind[i] != KIND_BACKGROUND && ( !rim || 2 * r->ink[i] >= r->ink_max[i] );
		}
	}
	int32_t best = -1, best_size = 0;
	for ( int32_t s = 0; s < r->n; ++s )
	{
		if ( r->region[s] == 1 )
		{
			int32_t size = flood4( r->region, w, h, s, 1, 2, r->queue );
			if ( size > best_size )
			{
				best = s, best_size = size;
			}
		}
	}
	if ( best < 0 )
	{
		return 0;
	}
	flood4( r->region, w, h, best, 2, 3, r->queue );
	for ( int32_t i = 0; i < r->n; ++i )
	{
		r->region[i] = r->region[i] == 3;
	}
	for ( int32_t i = 0; i < r->n; ++i )
	{
		int x = i % w, y = i / w;
		if ( ( x == 0 || y == 0 || x == w - 1 || y == h - 1 ) && r->region[i] == 0 )
		{
			flood4( r->region, w, h, i, 0, 2, r->queue );
		}
	}
	int32_t count = 0;
	for ( int32_t i = 0; i < r->n; ++i )
	{
		r->region[i] = r->region[i] != 2;
		count += r->region[i];
	}
	return count;
}

static int in_region( const reader* r, int x, int y )
{
	return x >= 0 && y >= 0 && x < r->w && y < r->h && r->region[y * r->w + x];
}

static double coverage( const reader* r, int x, int y )
{
	if ( x < 0 || y < 0 || x >= r->w || y >= r->h )
	{
		return 0.0;
	}
	int32_t i = y * r->w + x;
	return r->ink_max[i] > 0 ? fmin( 1.0, (double) r->ink[i] / r->ink_max[i] ) : 0.0;
}

typedef struct points
{
	double* xy;
	int32_t count, capacity;
} points;

static int push( points* p, double x, double y )
{
	if ( p->count == p->capacity )
	{
		int32_t capacity = p->capacity > 0 ? 2 * p->capacity : 1024;
		double* xy = realloc( p->xy, sizeof( double ) * 2 * (size_t) capacity );
		if ( xy == NULL )
		{
			return -1;
		}
		p->xy = xy;
		p->capacity = capacity;
	}
	p->xy[2 * p->count] = x;
	p->xy[2 * p->count + 1] = y;
	p->count += 1;
	return 0;
}

/* The inside and outside pixel of the crack leaving corner (cx, cy) in direction d (0 +x, 1 +y,
 * 2 -x, 3 -y; y down), with the inside on the walker's right as seen on screen. */
static void crack_pixels( int cx, int cy, int d, int* in, int* out )
{
	static const int table[4][4] = { { 0, 0, 0, -1 }, { -1, 0, 0, 0 }, { -1, -1, -1, 0 }, { 0, -1, -1, -1 } };
	in[0] = cx + table[d][0], in[1] = cy + table[d][1];
	out[0] = cx + table[d][2], out[1] = cy + table[d][3];
}

/* Marching squares along the region's boundary: follows the cracks between inside and outside
 * pixels (clockwise on screen) and puts one vertex on the segment joining the two pixel centres
 * of each crack, where the blade's coverage crosses 1/2. For an edge parallel to the crack,
 * inside coverage ci and outside co place it ci + co - 1/2 from the inside centre exactly. */
static sere_status trace_outline( reader* r, int32_t region_count, points* out )
{
	int32_t start = 0;
	while ( !r->region[start] )
	{
		start += 1;
	}
	const int sx = start % r->w, sy = start / r->w;
	static const int step[4][2] = { { 1, 0 }, { 0, 1 }, { -1, 0 }, { 0, -1 } };
	int cx = sx, cy = sy, d = 0;
	const int64_t limit = 4 * (int64_t) region_count + 8;
	do
	{
		int in[2], outside[2];
		crack_pixels( cx, cy, d, in, outside );
		double ci = fmax( 0.5, coverage( r, in[0], in[1] ) ), co = fmin( 0.5, coverage( r, outside[0], outside[1] ) );
		double t = fmin( 0.98, fmax( 0.02, ci + co - 0.5 ) );
		if ( push( out, in[0] + 0.5 + t * ( outside[0] - in[0] ), in[1] + 0.5 + t * ( outside[1] - in[1] ) ) != 0 )
		{
			return fail( r, SERE_ERR_MEMORY, "out of memory tracing the outline" );
		}
		cx += step[d][0], cy += step[d][1];
		int turned = 0;
		for ( int k = 3; k <= 5 && !turned; ++k ) /* left, straight, right */
		{
			int next = ( d + k ) % 4;
			crack_pixels( cx, cy, next, in, outside );
			if ( in_region( r, in[0], in[1] ) && !in_region( r, outside[0], outside[1] ) )
			{
				d = next;
				turned = 1;
			}
		}
		if ( !turned || out->count > limit )
		{
			return fail( r, SERE_ERR_GEOMETRY, "cannot trace the silhouette" );
		}
	} while ( cx != sx || cy != sy || d != 0 );
	return SERE_OK;
}

/* Taubin's lambda|mu smoothing: a shrinking Laplacian step then an inflating one, which removes
 * pixel-scale wiggles without shrinking the curve. Open polylines keep their end points. */
static void smooth( double* xy, int32_t n, int closed, double* scratch )
{
	static const double factor[2] = { 0.5, -0.53 };
	for ( int pass = 0; pass < SMOOTH_PASSES; ++pass )
	{
		for ( int f = 0; f < 2; ++f )
		{
			for ( int32_t i = 0; i < n; ++i )
			{
				int fixed = !closed && ( i == 0 || i == n - 1 );
				int32_t a = i > 0 ? i - 1 : n - 1, b = i + 1 < n ? i + 1 : 0;
				for ( int c = 0; c < 2; ++c )
				{
					double mean = 0.5 * ( xy[2 * a + c] + xy[2 * b + c] );
					scratch[2 * i + c] = fixed ? xy[2 * i + c] : xy[2 * i + c] + factor[f] * ( mean - xy[2 * i + c] );
				}
			}
			memcpy( xy, scratch, sizeof( double ) * 2 * (size_t) n );
		}
	}
}

static double segment_distance( const double* p, const double* a, const double* b )
{
	double ex = b[0] - a[0], ey = b[1] - a[1], length2 = ex * ex + ey * ey;
	double t = length2 > 0.0 ? ( ( p[0] - a[0] ) * ex + ( p[1] - a[1] ) * ey ) / length2 : 0.0;
	t = fmin( 1.0, fmax( 0.0, t ) );
	return hypot( a[0] + t * ex - p[0], a[1] + t * ey - p[1] );
}

/* Douglas-Peucker between vertices first and last (both kept), iteratively; stack holds
 * 2 (last - first + 1) ints. */
static void simplify( const double* xy, int32_t first, int32_t last, double tolerance, uint8_t* keep, int32_t* stack )
{
	int32_t top = 0;
	stack[top++] = first;
	stack[top++] = last;
	while ( top > 0 )
	{
		int32_t b = stack[--top], a = stack[--top];
		double worst = tolerance;
		int32_t at = -1;
		for ( int32_t i = a + 1; i < b; ++i )
		{
			double d = segment_distance( xy + 2 * i, xy + 2 * a, xy + 2 * b );
			if ( d > worst )
			{
				worst = d, at = i;
			}
		}
		if ( at >= 0 )
		{
			keep[at] = 1;
			stack[top++] = a;
			stack[top++] = at;
			stack[top++] = at;
			stack[top++] = b;
		}
	}
}

/* Simplifies a polyline keeping every vertex already marked in keep. */
static void simplify_between_kept( const double* xy, int32_t n, double tolerance, uint8_t* keep, int32_t* stack )
{
	int32_t a = 0;
	for ( int32_t b = 1; b < n; ++b )
	{
		if ( keep[b] )
		{
			simplify( xy, a, b, tolerance, keep, stack );
			a = b;
		}
	}
}

static double outline_distance( const double* xy, int32_t n, const double* p )
{
	double d = INFINITY;
	for ( int32_t i = 0, j = n - 1; i < n; j = i++ )
	{
		d = fmin( d, segment_distance( p, xy + 2 * j, xy + 2 * i ) );
	}
	return d;
}

static int outline_contains( const double* xy, int32_t n, const double* p )
{
	int in = 0;
	for ( int32_t i = 0, j = n - 1; i < n; j = i++ )
	{
		double xi = xy[2 * i], yi = xy[2 * i + 1], xj = xy[2 * j], yj = xy[2 * j + 1];
		if ( ( yi > p[1] ) != ( yj > p[1] ) && p[0] < xj + ( p[1] - yj ) * ( xi - xj ) / ( yi - yj ) )
		{
			in = !in;
		}
	}
	return in;
}

/* The outline in leaf coordinates, the base as vertex 0, and the pixel mapping. */
typedef struct outline
{
	double* xy;
	int32_t count;
	double base_px, base_py, scale; /* scale: pixels per leaf unit */
	double dot_distance;			/* from the base dot's centre to the traced outline, px */
} outline;

/* Smooths and simplifies the traced loop (each optional), puts the base where the outline
 * passes nearest the dot, maps to leaf coordinates and orients counter-clockwise. Fails with
 * SERE_ERR_GEOMETRY if the result is not a simple polygon (a sub-pixel neck), so the caller can
 * retry with less processing. */
static sere_status make_outline( const points* traced, int do_smooth, int do_simplify, double dot_x, double dot_y,
								 outline* o )
{
	const int32_t n = traced->count;
	double* loop = malloc( sizeof( double ) * 2 * ( (size_t) n + 2 ) );
	double* scratch = malloc( sizeof( double ) * 2 * ( (size_t) n + 2 ) );
	uint8_t* keep = calloc( (size_t) n + 1, 1 );
	int32_t* stack = malloc( sizeof( int32_t ) * 2 * ( (size_t) n + 2 ) );
	o->xy = malloc( sizeof( double ) * 2 * ( (size_t) n + 2 ) );
	if ( loop == NULL || scratch == NULL || keep == NULL || stack == NULL || o->xy == NULL )
	{
		free( loop ), free( scratch ), free( keep ), free( stack ), free( o->xy );
		o->xy = NULL;
		return SERE_ERR_MEMORY;
	}
	memcpy( loop, traced->xy, sizeof( double ) * 2 * (size_t) n );
	if ( do_smooth )
	{
		smooth( loop, n, 1, scratch );
	}
	loop[2 * n] = loop[0], loop[2 * n + 1] = loop[1];
	if ( do_simplify )
	{
		int32_t far = 0;
		for ( int32_t i = 1; i < n; ++i )
		{
			if ( hypot( loop[2 * i] - loop[0], loop[2 * i + 1] - loop[1] ) >
				 hypot( loop[2 * far] - loop[0], loop[2 * far + 1] - loop[1] ) )
			{
				far = i;
			}
		}
		keep[0] = keep[far] = keep[n] = 1;
		simplify_between_kept( loop, n + 1, OUTLINE_TOLERANCE, keep, stack );
	}
	else
	{
		memset( keep, 1, (size_t) n + 1 );
	}
	int32_t m = 0;
	for ( int32_t i = 0; i < n; ++i )
	{
		if ( keep[i] )
		{
			scratch[2 * m] = loop[2 * i], scratch[2 * m + 1] = loop[2 * i + 1];
			m += 1;
		}
	}
	/* The base: the outline point nearest the dot's centre, inserted as a vertex. */
	const double dot[2] = { dot_x, dot_y };
	int32_t segment = 0;
	double best = INFINITY;
	for ( int32_t i = 0; i < m; ++i )
	{
		double d = segment_distance( dot, scratch + 2 * i, scratch + 2 * ( ( i + 1 ) % m ) );
		if ( d < best )
		{
			best = d, segment = i;
		}
	}
	const double* a = scratch + 2 * segment;
	const double* b = scratch + 2 * ( ( segment + 1 ) % m );
	double ex = b[0] - a[0], ey = b[1] - a[1], length2 = ex * ex + ey * ey;
	double t =
		length2 > 0.0 ? fmin( 1.0, fmax( 0.0, ( ( dot_x - a[0] ) * ex + ( dot_y - a[1] ) * ey ) / length2 ) ) : 0.0;
	double base[2] = { a[0] + t * ex, a[1] + t * ey };
	int32_t first = segment; /* the vertex the loop starts from after the base */
	/* Within a simplification tolerance of a vertex the base is that vertex, not a new one that
	 * would leave a sliver of an edge. */
	int inserted = 0;
	if ( hypot( base[0] - a[0], base[1] - a[1] ) <= OUTLINE_TOLERANCE )
	{
		base[0] = a[0], base[1] = a[1];
	}
	else if ( hypot( base[0] - b[0], base[1] - b[1] ) <= OUTLINE_TOLERANCE )
	{
		base[0] = b[0], base[1] = b[1];
		first = ( segment + 1 ) % m;
	}
	else
	{
		inserted = 1;
		first = ( segment + 1 ) % m;
	}
	double scale = 0.0;
	for ( int32_t i = 0; i < m; ++i )
	{
		scale = fmax( scale, hypot( scratch[2 * i] - base[0], scratch[2 * i + 1] - base[1] ) );
	}
	/* y flips up (the clockwise-on-screen trace becomes counter-clockwise; checked below): vertex 0
	 * is the base, then the loop from `first` on, mapped by x = (px - bx) / s, y = (by - py) / s. */
	int32_t count = 0;
	o->xy[2 * count] = 0.0, o->xy[2 * count + 1] = 0.0;
	count += 1;
	for ( int32_t k = 0; k < m - ( inserted ? 0 : 1 ); ++k )
	{
		const double* p = scratch + 2 * ( ( first + k + ( inserted ? 0 : 1 ) ) % m );
		o->xy[2 * count] = ( p[0] - base[0] ) / scale;
		o->xy[2 * count + 1] = ( base[1] - p[1] ) / scale;
		count += 1;
	}
	free( loop ), free( scratch ), free( keep ), free( stack );
	double twice_area = 0.0;
	for ( int32_t i = 0, j = count - 1; i < count; j = i++ )
	{
		twice_area += o->xy[2 * j] * o->xy[2 * i + 1] - o->xy[2 * i] * o->xy[2 * j + 1];
	}
	for ( int32_t i = 1, j = count - 1; twice_area < 0.0 && i < j; ++i, --j )
	{
		double x = o->xy[2 * i], y = o->xy[2 * i + 1];
		o->xy[2 * i] = o->xy[2 * j], o->xy[2 * i + 1] = o->xy[2 * j + 1];
		o->xy[2 * j] = x, o->xy[2 * j + 1] = y;
	}
	o->count = count;
	o->base_px = base[0], o->base_py = base[1], o->scale = scale;
	o->dot_distance = best;
	sere_leaf_shape shape = { 0.0, 0.0, count, o->xy, 0, NULL, 0, NULL };
	sere_shape_check check;
	if ( sere_shape_validate( &shape, &check ) != SERE_OK )
	{
		free( o->xy );
		o->xy = NULL;
		return SERE_ERR_GEOMETRY;
	}
	return SERE_OK;
}

/* Zhang-Suen thinning of the pixels listed in live (count of them; pixels outside the image
 * count as empty). Each sub-iteration marks pixels 2 and deletes them at its end, so every test
 * in it sees its starting image; the list shrinks with the strokes, so the cost follows the
 * vein pixels, not the image. */
static void thin( uint8_t* m, int w, int h, int32_t* live, int32_t count )
{
	/* P2..P9 clockwise from north, P2 repeated to close the ring */
	static const int ring[9][2] = { { 0, -1 }, { 1, -1 }, { 1, 0 },	  { 1, 1 }, { 0, 1 },
									{ -1, 1 }, { -1, 0 }, { -1, -1 }, { 0, -1 } };
	int changed = 1;
	while ( changed )
	{
		changed = 0;
		for ( int pass = 0; pass < 2; ++pass )
		{
			for ( int32_t k = 0; k < count; ++k )
			{
				int x = live[k] % w, y = live[k] / w;
				int p[9];
				for ( int j = 0; j < 9; ++j )
				{
					int qx = x + ring[j][0], qy = y + ring[j][1];
					p[j] = qx >= 0 && qy >= 0 && qx < w && qy < h && m[qy * w + qx] != 0;
				}
				int neighbors = 0, transitions = 0;
				for ( int j = 0; j < 8; ++j )
				{
					neighbors += p[j];
					transitions += !p[j] && p[j + 1];
				}
				int c = pass == 0 ? !( p[0] && p[2] && p[4] ) : !( p[0] && p[2] && p[6] );
				int e = pass == 0 ? !( p[2] && p[4] && p[6] ) : !( p[0] && p[4] && p[6] );
				if ( neighbors >= 2 && neighbors <= 6 && transitions == 1 && c && e )
				{
					m[live[k]] = 2;
				}
			}
			int32_t kept = 0;
			for ( int32_t k = 0; k < count; ++k )
			{
				if ( m[live[k]] == 2 )
				{
					m[live[k]] = 0;
					changed = 1;
				}
				else
				{
					live[kept++] = live[k];
				}
			}
			count = kept;
		}
	}
}

/* A vein while it is built: nodes [first, first + count) of the node arrays. Node 0 is the base
 * (skeleton index -1) or the pixel on the parent it branches from, at the parent's node attach. */
typedef struct vein_build
{
	int32_t first, count, parent, attach, order;
} vein_build;

typedef struct tip
{
	double length;
	int32_t index;
} tip;

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

/* The skeleton graph and the veins read from it. Skeleton pixels are numbered in raster order;
 * the pixel -> number map is the reader's queue. */
typedef struct veins_work
{
	int32_t count;
	int32_t* pixel;
	int32_t* component;
	int32_t* bfs_parent;
	int32_t* order_queue;
	double* dist;
	uint8_t* children;
	int32_t* on_vein;
	int32_t* node_pos;
	tip* tips;
	int32_t* path;
	int32_t* node_skeleton;
	double* node_xy;
	uint8_t* node_keep;
	int32_t* node_final;
	vein_build* veins;
	int32_t vein_count, node_count;
	double* scratch;
	int32_t* stack;
} veins_work;

static void veins_work_free( veins_work* v )
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
static sere_status skeleton_veins( reader* r, veins_work* v, double dot_x, double dot_y, double dot_radius,
								   double base_px, double base_py )
{
	const int w = r->w, h = r->h;
	/* the region array becomes the vein mask: red pixels of the silhouette */
	int32_t stroke_pixels = 0;
	for ( int32_t i = 0; i < r->n; ++i )
	{
		uint8_t vein = r->region[i] && r->kind[i] == KIND_VEIN;
		r->region[i] = vein;
		if ( vein )
		{
			r->queue[stroke_pixels++] = i;
		}
	}
	thin( r->region, w, h, r->queue, stroke_pixels );
	int32_t count = 0;
	for ( int32_t i = 0; i < r->n; ++i )
	{
		r->queue[i] = r->region[i] ? count++ : -1;
	}
	if ( count == 0 )
	{
		return fail( r, SERE_ERR_GEOMETRY, "no veins: the red marks are too small to be strokes" );
	}
	sere_status status = veins_work_create( v, count );
	if ( status != SERE_OK )
	{
		return fail( r, status, "out of memory for the vein skeleton" );
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

	/* Components: each must come within reach of the base dot, unless it is a speck. */
	int32_t neighbors[8];
	for ( int32_t s = 0; s < count; ++s )
	{
		v->component[s] = -1;
	}
	int32_t components = 0, sources = 0, stray = -1;
	double nearest_any = INFINITY;
	for ( int32_t s = 0; s < count; ++s )
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
			v->path[sources++] = nearest; /* the component's root */
		}
		else if ( tail >= DUST_PIXELS && stray < 0 )
		{
			stray = v->pixel[nearest];
		}
		components += 1;
	}
	if ( sources == 0 )
	{
		return fail( r, SERE_ERR_GEOMETRY,
					 "the veins do not reach the base: the nearest vein pixel is %.0f px from the blue dot (at most "
					 "%.0f)",
					 nearest_any, reach );
	}
	if ( stray >= 0 )
	{
		return fail( r, SERE_ERR_GEOMETRY,
					 "the vein stroke near pixel (%d, %d) is not connected to the veins that start at the base",
					 stray % w, stray / w );
	}

	/* Breadth-first trees from the roots; dist is the path length from the dot's centre. */
	int32_t head = 0, tail = 0;
	for ( int32_t s = 0; s < count; ++s )
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
	int32_t tip_count = 0;
	for ( int32_t k = 0; k < tail; ++k )
	{
		int32_t s = v->order_queue[k];
		if ( v->children[s] == 0 )
		{
			v->tips[tip_count++] = ( tip ){ v->dist[s], s };
		}
	}
	qsort( v->tips, (size_t) tip_count, sizeof( tip ), compare_tips );

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
	if ( v->vein_count == 0 )
	{
		return fail( r, SERE_ERR_GEOMETRY, "no veins: the red strokes at the base are shorter than %.0f px", spur );
	}

	/* Pixel paths to smoothed, simplified polylines (px). A branch's node 0 takes its parent's
	 * final position at the attach node, so it lies exactly on the parent. */
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
		smooth( xy, vein->count, 0, v->scratch );
	}
	for ( int32_t e = 0; e < v->vein_count; ++e )
	{
		const vein_build* vein = v->veins + e;
		v->node_keep[vein->first] = v->node_keep[vein->first + vein->count - 1] = 1;
		simplify_between_kept( v->node_xy + 2 * vein->first, vein->count, VEIN_TOLERANCE, v->node_keep + vein->first,
							   v->stack );
	}
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
		if ( outline_contains( o->xy, o->count, p ) && outline_distance( o->xy, o->count, p ) > margin )
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
static sere_status place_veins( reader* r, veins_work* v, const outline* o, sere_leaf_file* leaf )
{
	const double margin = fmax( MARGIN_FRACTION, MARGIN_MIN_PIXELS / o->scale );
	const double quarter = 0.25 / o->scale, shortest = 2.0 / o->scale;
	leaf->veins = malloc( sizeof( sere_vein ) * (size_t) v->vein_count );
	leaf->vein_xy = malloc( sizeof( double ) * 2 * ( (size_t) v->node_count + (size_t) v->vein_count ) );
	int32_t* final_index = malloc( sizeof( int32_t ) * (size_t) v->vein_count );
	if ( leaf->veins == NULL || leaf->vein_xy == NULL || final_index == NULL )
	{
		free( final_index );
		return fail( r, SERE_ERR_MEMORY, "out of memory for the veins" );
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
			int inside = outline_contains( o->xy, o->count, p );
			double d = outline_distance( o->xy, o->count, p );
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
				if ( !leaving && ( m > 1 || ( outline_contains( o->xy, o->count, previous ) &&
											  outline_distance( o->xy, o->count, previous ) > margin ) ) )
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
		return fail( r, SERE_ERR_GEOMETRY, "no veins left: every vein runs within %.0f px of the outline",
					 margin * o->scale );
	}
	leaf->shape.vein_count = kept_veins;
	leaf->shape.veins = leaf->veins;
	leaf->shape.vein_point_count = points;
	leaf->shape.vein_xy = leaf->vein_xy;
	return SERE_OK;
}

/* The largest 8-connected blue blob: its centre and radius (from its area), px. */
static int base_dot( reader* r, double* x, double* y, double* radius )
{
	int32_t best = 0;
	const int w = r->w, h = r->h;
	for ( int32_t i = 0; i < r->n; ++i )
	{
		r->ink_max[i] = r->region[i] && r->kind[i] == KIND_BASE;
	}
	for ( int32_t s = 0; s < r->n; ++s )
	{
		if ( r->ink_max[s] != 1 )
		{
			continue;
		}
		int32_t head = 0, tail = 0;
		double sx = 0.0, sy = 0.0;
		r->ink_max[s] = 2;
		r->queue[tail++] = s;
		while ( head < tail )
		{
			int32_t p = r->queue[head++];
			int px = p % w, py = p / w;
			sx += px + 0.5, sy += py + 0.5;
			for ( int dy = -1; dy <= 1; ++dy )
			{
				for ( int dx = -1; dx <= 1; ++dx )
				{
					int qx = px + dx, qy = py + dy;
					if ( qx >= 0 && qy >= 0 && qx < w && qy < h && r->ink_max[qy * w + qx] == 1 )
					{
						r->ink_max[qy * w + qx] = 2;
						r->queue[tail++] = qy * w + qx;
					}
				}
			}
		}
		if ( tail > best )
		{
			best = tail;
			*x = sx / tail, *y = sy / tail;
		}
	}
	*radius = sqrt( best / 3.14159265358979323846 );
	return best;
}

/* A reader for one public call: the caller's error buffer cleared, the path named in messages. */
static reader reader_start( const char* path, char* err, size_t err_size )
{
	if ( err != NULL && err_size > 0 )
	{
		err[0] = '\0';
	}
	reader r = { 0 };
	r.path = path != NULL ? path : "(null)";
	r.err = err;
	r.err_size = err_size;
	return r;
}

static void reader_free( reader* r )
{
	free( r->kind ), free( r->ink ), free( r->ink_max ), free( r->region ), free( r->queue ), free( r->rgba );
}

/* Loads the PNG, classifies its pixels, finds the silhouette and traces its outline into
 * traced; no_leaf names what was missing when the silhouette is too small. The caller frees
 * traced.xy and the reader's buffers whatever the status. */
static sere_status trace_png( reader* r, points* traced, const char* no_leaf )
{
	sere_status status = load_png( r );
	if ( status != SERE_OK )
	{
		return status;
	}
	r->kind = malloc( (size_t) r->n );
	r->ink = malloc( (size_t) r->n );
	r->ink_max = malloc( (size_t) r->n );
	r->region = malloc( (size_t) r->n );
	r->queue = malloc( sizeof( int32_t ) * (size_t) r->n );
	if ( r->kind == NULL || r->ink == NULL || r->ink_max == NULL || r->region == NULL || r->queue == NULL )
	{
		return fail( r, SERE_ERR_MEMORY, "out of memory for a %d x %d image", r->w, r->h );
	}
	classify( r );
	free( r->rgba );
	r->rgba = NULL;
	int32_t blade = silhouette( r );
	if ( blade < MIN_BLADE_PIXELS )
	{
		return fail( r, SERE_ERR_GEOMETRY, "no leaf: fewer than %d %s", MIN_BLADE_PIXELS, no_leaf );
	}
	return trace_outline( r, blade, traced );
}

sere_status sere_leaf_from_png_mapped( const char* path, sere_leaf_file* leaf, sere_leaf_image_map* map, char* err,
									   size_t err_size )
{
	reader r = reader_start( path, err, err_size );
	if ( path == NULL || leaf == NULL )
	{
		return fail( &r, SERE_ERR_ARGUMENT, path == NULL ? "no file name" : "no leaf to fill" );
	}
	memset( leaf, 0, sizeof( *leaf ) );
	if ( map != NULL )
	{
		memset( map, 0, sizeof( *map ) );
	}
	points traced = { 0 };
	outline o = { 0 };
	veins_work v = { 0 };
	sere_status status = trace_png( &r, &traced, "blade pixels (the blade is any color but white or transparent)" );
	if ( status != SERE_OK )
	{
		goto done;
	}
	/* the coverage (ink_max) is no longer needed: it becomes the base dot's mask */
	double dot_x = 0.0, dot_y = 0.0, dot_radius = 0.0;
	int veins_found = 0;
	for ( int32_t i = 0; i < r.n && !veins_found; ++i )
	{
		veins_found = r.region[i] && r.kind[i] == KIND_VEIN;
	}
	if ( !veins_found )
	{
		status = fail( &r, SERE_ERR_GEOMETRY,
					   "no veins: draw them as red strokes (R > 200, G < 80, B < 80) over the blade" );
		goto done;
	}
	if ( base_dot( &r, &dot_x, &dot_y, &dot_radius ) == 0 )
	{
		int elsewhere = 0;
		for ( int32_t i = 0; i < r.n && !elsewhere; ++i )
		{
			elsewhere = r.kind[i] == KIND_BASE;
		}
		status = fail( &r, SERE_ERR_GEOMETRY, "no base: %s",
					   elsewhere ? "the blue dot is off the leaf; draw it inside the blade, touching the margin"
								 : "draw a blue dot (B > 200, R < 80, G < 80) touching the margin at the petiole" );
		goto done;
	}
	/* Full processing first; a sub-pixel neck can make the simplified loop touch itself, then
	 * less processing is used (the raw marching-squares loop is always simple). */
	status = SERE_ERR_GEOMETRY;
	for ( int level = 0; level < 3 && status == SERE_ERR_GEOMETRY; ++level )
	{
		status = make_outline( &traced, level < 1, level < 2, dot_x, dot_y, &o );
	}
	if ( status != SERE_OK )
	{
		status = status == SERE_ERR_MEMORY ? fail( &r, status, "out of memory for the outline" )
										   : fail( &r, status, "the traced outline is not a simple polygon" );
		goto done;
	}
	if ( o.dot_distance > dot_radius + 3.0 )
	{
		int32_t x = (int32_t) dot_x, y = (int32_t) dot_y;
		status = fail( &r, SERE_ERR_GEOMETRY,
					   "the blue base dot at pixel (%d, %d) is %.0f px inside the margin: draw it touching the margin",
					   x, y, o.dot_distance );
		goto done;
	}
	status = skeleton_veins( &r, &v, dot_x, dot_y, dot_radius, o.base_px, o.base_py );
	if ( status != SERE_OK )
	{
		goto done;
	}
	status = place_veins( &r, &v, &o, leaf );
	if ( status != SERE_OK )
	{
		goto done;
	}
	leaf->outline_xy = o.xy;
	o.xy = NULL;
	leaf->shape.base_x = 0.0;
	leaf->shape.base_y = 0.0;
	leaf->shape.outline_count = o.count;
	leaf->shape.outline_xy = leaf->outline_xy;
	/* named like a .leaf file: the file name without its extension */
	const char* slash = strrchr( r.path, '/' );
	const char* file = slash != NULL ? slash + 1 : r.path;
	const char* dot = strrchr( file, '.' );
	int length = dot != NULL && dot > file ? (int) ( dot - file ) : (int) strlen( file );
	snprintf( leaf->name, sizeof( leaf->name ), "%.*s", length, file );
	sere_shape_check check;
	status = sere_shape_validate( &leaf->shape, &check );
	if ( status != SERE_OK )
	{
		status = fail( &r, status, "the traced leaf is not usable: %s", sere_shape_problem_text( check.problem ) );
		goto done;
	}
	if ( map != NULL )
	{
		*map = ( sere_leaf_image_map ){ r.w, r.h, o.base_px, o.base_py, o.scale };
	}

done:
	if ( status != SERE_OK )
	{
		sere_leaf_file_free( leaf );
	}
	veins_work_free( &v );
	free( o.xy );
	free( traced.xy );
	reader_free( &r );
	return status;
}

sere_status sere_leaf_from_png( const char* path, sere_leaf_file* leaf, char* err, size_t err_size )
{
	return sere_leaf_from_png_mapped( path, leaf, NULL, err, err_size );
}

/* Without a blue dot the base is where a leaf drawn petiole down has its petiole: the outline
 * point nearest the middle of the bottom of the silhouette's bounding box. */
static void bottom_middle( const points* traced, double* x, double* y )
{
	double x_min = INFINITY, x_max = -INFINITY, y_max = -INFINITY;
	for ( int32_t i = 0; i < traced->count; ++i )
	{
		x_min = fmin( x_min, traced->xy[2 * i] );
		x_max = fmax( x_max, traced->xy[2 * i] );
		y_max = fmax( y_max, traced->xy[2 * i + 1] );
	}
	*x = 0.5 * ( x_min + x_max );
	*y = y_max;
}

sere_status sere_silhouette_from_png( const char* path, double** xy, int32_t* count, int32_t* width, int32_t* height,
									  char* err, size_t err_size )
{
	reader r = reader_start( path, err, err_size );
	if ( path == NULL || xy == NULL || count == NULL || width == NULL || height == NULL )
	{
		return fail( &r, SERE_ERR_ARGUMENT, "no file name or no place for the outline" );
	}
	*xy = NULL;
	*count = 0;
	points traced = { 0 };
	outline o = { 0 };
	sere_status status = trace_png( &r, &traced, "non-background pixels (background is white or transparent)" );
	if ( status != SERE_OK )
	{
		goto done;
	}
	double base_x = 0.0, base_y = 0.0, radius = 0.0;
	if ( base_dot( &r, &base_x, &base_y, &radius ) == 0 )
	{
		bottom_middle( &traced, &base_x, &base_y );
	}
	status = SERE_ERR_GEOMETRY;
	for ( int level = 0; level < 3 && status == SERE_ERR_GEOMETRY; ++level )
	{
		status = make_outline( &traced, level < 1, level < 2, base_x, base_y, &o );
	}
	if ( status != SERE_OK )
	{
		status = status == SERE_ERR_MEMORY ? fail( &r, status, "out of memory for the outline" )
										   : fail( &r, status, "the traced outline is not a simple polygon" );
		goto done;
	}
	/* back from leaf units to pixels (make_outline's mapping inverted) */
	for ( int32_t i = 0; i < o.count; ++i )
	{
		double x = o.xy[2 * i], y = o.xy[2 * i + 1];
		o.xy[2 * i] = o.base_px + x * o.scale;
		o.xy[2 * i + 1] = o.base_py - y * o.scale;
	}
	*xy = o.xy;
	*count = o.count;
	*width = r.w;
	*height = r.h;
	o.xy = NULL;

done:
	free( o.xy );
	free( traced.xy );
	reader_free( &r );
	return status;
}

sere_status sere_png_read_gray( const char* path, float** gray, int32_t* width, int32_t* height, char* err,
								size_t err_size )
{
	reader r = reader_start( path, err, err_size );
	if ( path == NULL || gray == NULL || width == NULL || height == NULL )
	{
		return fail( &r, SERE_ERR_ARGUMENT, "no file name or no place for the image" );
	}
	*gray = NULL;
	sere_status status = load_png( &r );
	if ( status != SERE_OK )
	{
		return status;
	}
	float* g = malloc( sizeof( float ) * (size_t) r.n );
	if ( g == NULL )
	{
		free( r.rgba );
		return fail( &r, SERE_ERR_MEMORY, "out of memory for a %d x %d image", r.w, r.h );
	}
	for ( int32_t i = 0; i < r.n; ++i )
	{
		const uint8_t* p = r.rgba + 4 * (size_t) i;
		g[i] = (float) ( ( 0.299 * p[0] + 0.587 * p[1] + 0.114 * p[2] ) * p[3] / ( 255.0 * 255.0 ) );
	}
	free( r.rgba );
	*gray = g;
	*width = r.w;
	*height = r.h;
	return SERE_OK;
}
