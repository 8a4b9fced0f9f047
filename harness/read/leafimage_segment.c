/* sere harness — Segmentation: pixel classes, the silhouette and the base dot. */
#include "read/leafimage_shared.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

void leafimage_classify( reader* r )
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

/* The running maximum of 5 samples along each of `lines` lines of `length` samples, sample k of
 * line j at j * line_step + k * step: one pass of max_filter. */
static void max_pass( const uint8_t* in, uint8_t* out, int lines, int length, int line_step, int step )
{
	for ( int j = 0; j < lines; ++j )
	{
		for ( int i = 0; i < length; ++i )
		{
			uint8_t m = 0;
			for ( int k = i - 2; k <= i + 2; ++k )
			{
				if ( k >= 0 && k < length && in[j * line_step + k * step] > m )
				{
					m = in[j * line_step + k * step];
				}
			}
			out[j * line_step + i * step] = m;
		}
	}
}

/* 5 x 5 running maximum, separably (rows, then columns); scratch is n bytes. */
static void max_filter( const uint8_t* in, uint8_t* scratch, uint8_t* out, int w, int h )
{
	max_pass( in, scratch, h, w, w, 1 );
	max_pass( scratch, out, w, h, 1, w );
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
int32_t leafimage_silhouette( reader* r )
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

int leafimage_base_dot( reader* r, double* x, double* y, double* radius )
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
