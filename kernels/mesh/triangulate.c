#include "mesh/triangulate.h"

#include "core/array.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Coordinates are snapped to a 2^26 integer grid over the bounding box, so orient2d fits in
 * int64 and incircle in int128 exactly (the three super-triangle corners lie within ±2^28:
 * differences < 2^30, lifted terms < 2^61, products < 2^122). */
#define GRID_BITS	26
#define SUPER_COORD ( (int64_t) 1 << 28 )

/* gcc and clang provide 128-bit integers; __extension__ keeps -Wpedantic quiet about it. */
__extension__ typedef __int128 int128;

typedef struct ipoint
{
	int64_t x, y;
} ipoint;

static int64_t orient( ipoint a, ipoint b, ipoint c )
{
	return ( b.x - a.x ) * ( c.y - a.y ) - ( b.y - a.y ) * ( c.x - a.x );
}

static int sign128( int128 v )
{
	return ( v > 0 ) - ( v < 0 );
}

/* > 0 when d lies strictly inside the circumcircle of the counter-clockwise triangle abc. */
static int incircle( ipoint a, ipoint b, ipoint c, ipoint d )
{
	int64_t adx = a.x - d.x, ady = a.y - d.y;
	int64_t bdx = b.x - d.x, bdy = b.y - d.y;
	int64_t cdx = c.x - d.x, cdy = c.y - d.y;
	int128 alift = (int128) adx * adx + (int128) ady * ady;
	int128 blift = (int128) bdx * bdx + (int128) bdy * bdy;
	int128 clift = (int128) cdx * cdx + (int128) cdy * cdy;
	int128 bc = (int128) bdx * cdy - (int128) cdx * bdy;
	int128 ca = (int128) cdx * ady - (int128) adx * cdy;
	int128 ab = (int128) adx * bdy - (int128) bdx * ady;
	return sign128( alift * bc + blift * ca + clift * ab );
}

/* Triangle t has corners v[3t..3t+2] counter-clockwise and neighbours n[3t+k] across the edge
 * opposite corner k (-1 on the hull). Edge k of t joins v[k+1] and v[k+2]. */
typedef struct mesh
{
	ipoint* p;
	int32_t point_count; /* input vertices, then the three super corners */
	int32_t* v;
	int32_t* n;
	uint8_t* fixed; /* per (t, k): edge k is constrained */
	int32_t count, capacity;
	int32_t* stack;
	int32_t stack_count, stack_capacity;
	int32_t last;
} mesh;

static int next3( int k )
{
	return k == 2 ? 0 : k + 1;
}

static int prev3( int k )
{
	return k == 0 ? 2 : k - 1;
}

static int grow( mesh* m, int32_t extra )
{
	if ( m->count + extra <= m->capacity )
	{
		return 0;
	}
	int32_t capacity = 2 * ( m->count + extra );
	int32_t* v = sere_array_resize( m->v, capacity, 3 * sizeof( int32_t ) );
	m->v = v != NULL ? v : m->v;
	int32_t* n = v != NULL ? sere_array_resize( m->n, capacity, 3 * sizeof( int32_t ) ) : NULL;
	m->n = n != NULL ? n : m->n;
	uint8_t* fixed = n != NULL ? sere_array_resize( m->fixed, capacity, 3 ) : NULL;
	if ( fixed == NULL )
	{
		return -1;
	}
	m->fixed = fixed;
	m->capacity = capacity;
	return 0;
}

static int push( mesh* m, int32_t value )
{
	int32_t* stack = sere_array_append( m->stack, &m->stack_count, &m->stack_capacity, 1024, &value, sizeof( value ) );
	m->stack = stack != NULL ? stack : m->stack;
	return stack != NULL ? 0 : -1;
}

static int32_t add_triangle( mesh* m, int32_t a, int32_t b, int32_t c )
{
	int32_t t = m->count++;
	m->v[3 * t] = a, m->v[3 * t + 1] = b, m->v[3 * t + 2] = c;
	m->n[3 * t] = m->n[3 * t + 1] = m->n[3 * t + 2] = -1;
	m->fixed[3 * t] = m->fixed[3 * t + 1] = m->fixed[3 * t + 2] = 0;
	return t;
}

/* The edge index of neighbour u that points back to t. */
static int back_edge( const mesh* m, int32_t u, int32_t t )
{
	return m->n[3 * u] == t ? 0 : ( m->n[3 * u + 1] == t ? 1 : 2 );
}

static void link( mesh* m, int32_t t, int k, int32_t u, int j )
{
	if ( t >= 0 )
	{
		m->n[3 * t + k] = u;
	}
	if ( u >= 0 )
	{
		m->n[3 * u + j] = t;
	}
}

/* Flips the edge k of t with its neighbour; returns the neighbour. After the flip t and u
 * share the new diagonal; t keeps corner v[k] of t. */
static int32_t flip( mesh* m, int32_t t, int k )
{
	int32_t u = m->n[3 * t + k];
	int j = back_edge( m, u, t );
	int32_t a = m->v[3 * t + k];
	int32_t b = m->v[3 * t + next3( k )];
	int32_t c = m->v[3 * t + prev3( k )];
	int32_t d = m->v[3 * u + j];
	/* Outer neighbours and their constraint flags. */
	int32_t n_ab = m->n[3 * t + prev3( k )], n_ca = m->n[3 * t + next3( k )];
	int32_t n_bd = m->n[3 * u + next3( j )], n_dc = m->n[3 * u + prev3( j )];
	uint8_t f_ab = m->fixed[3 * t + prev3( k )], f_ca = m->fixed[3 * t + next3( k )];
	uint8_t f_bd = m->fixed[3 * u + next3( j )], f_dc = m->fixed[3 * u + prev3( j )];
	/* Around the quad a b d c (counter-clockwise: t = a b c, u = c b d): new t = a b d, u = a d c. */
	int ab_back = n_ab >= 0 ? back_edge( m, n_ab, t ) : 0;
	int ca_back = n_ca >= 0 ? back_edge( m, n_ca, t ) : 0;
	int bd_back = n_bd >= 0 ? back_edge( m, n_bd, u ) : 0;
	int dc_back = n_dc >= 0 ? back_edge( m, n_dc, u ) : 0;
	m->v[3 * t] = a, m->v[3 * t + 1] = b, m->v[3 * t + 2] = d;
	m->v[3 * u] = a, m->v[3 * u + 1] = d, m->v[3 * u + 2] = c;
	/* t = (a, b, d): edge 0 = b-d, edge 1 = d-a (shared with u), edge 2 = a-b. */
	link( m, t, 0, n_bd, bd_back );
	link( m, t, 2, n_ab, ab_back );
	m->fixed[3 * t] = f_bd, m->fixed[3 * t + 2] = f_ab, m->fixed[3 * t + 1] = 0;
	/* u = (a, d, c): edge 0 = d-c, edge 1 = c-a, edge 2 = a-d (shared with t). */
	link( m, u, 0, n_dc, dc_back );
	link( m, u, 1, n_ca, ca_back );
	m->fixed[3 * u] = f_dc, m->fixed[3 * u + 1] = f_ca, m->fixed[3 * u + 2] = 0;
	m->n[3 * t + 1] = u;
	m->n[3 * u + 2] = t;
	return u;
}

/* Writes triangle t and points each outer neighbour's matching edge back at it. back[k] is
 * the edge of n[k] that faces t (ignored when n[k] < 0). */
static void set_triangle( mesh* m, int32_t t, const int32_t v[3], const int32_t n[3], const int back[3],
						  const uint8_t f[3] )
{
	for ( int k = 0; k < 3; ++k )
	{
		m->v[3 * t + k] = v[k];
		m->n[3 * t + k] = n[k];
		m->fixed[3 * t + k] = f[k];
		if ( n[k] >= 0 && back[k] >= 0 )
		{
			m->n[3 * n[k] + back[k]] = t;
		}
	}
}

static int legalize( mesh* m, int32_t* vt )
{
	while ( m->stack_count > 0 )
	{
		int32_t code = m->stack[--m->stack_count];
		int32_t t = code / 3;
		int k = code % 3;
		int32_t u = m->n[3 * t + k];
		if ( u < 0 || m->fixed[3 * t + k] )
		{
			continue;
		}
		int j = back_edge( m, u, t );
		int32_t a = m->v[3 * t + k], b = m->v[3 * t + next3( k )], c = m->v[3 * t + prev3( k )];
		int32_t d = m->v[3 * u + j];
		if ( incircle( m->p[a], m->p[b], m->p[c], m->p[d] ) <= 0 )
		{
			continue;
		}
		flip( m, t, k );
		vt[a] = t, vt[b] = t, vt[d] = t, vt[c] = u;
		/* The two edges of the quad not touching a may now be illegal: t's b–d, u's d–c. */
		if ( push( m, 3 * t + 0 ) != 0 || push( m, 3 * u + 0 ) != 0 )
		{
			return -1;
		}
	}
	return 0;
}

/* Walks to the triangle containing p; returns it and the per-edge orientations. */
static int32_t locate( const mesh* m, int32_t start, ipoint p, int64_t o[3] )
{
	int32_t t = start;
	uint32_t turn = 0;
	for ( ;; )
	{
		int moved = 0;
		int first = (int) ( turn++ % 3 );
		for ( int q = 0; q < 3; ++q )
		{
			int k = ( first + q ) % 3;
			ipoint b = m->p[m->v[3 * t + next3( k )]], c = m->p[m->v[3 * t + prev3( k )]];
			o[k] = orient( b, c, p );
			if ( o[k] < 0 && m->n[3 * t + k] >= 0 )
			{
				t = m->n[3 * t + k];
				moved = 1;
				break;
			}
		}
		if ( !moved )
		{
			for ( int k = 0; k < 3; ++k )
			{
				o[k] = orient( m->p[m->v[3 * t + next3( k )]], m->p[m->v[3 * t + prev3( k )]], p );
			}
			return t;
		}
	}
}

static int insert_point( mesh* m, int32_t* vt, int32_t i )
{
	int64_t o[3];
	int32_t t = locate( m, m->last, m->p[i], o );
	if ( grow( m, 2 ) != 0 )
	{
		return -1;
	}
	int zero = -1;
	for ( int k = 0; k < 3; ++k )
	{
		if ( o[k] == 0 )
		{
			zero = k;
		}
	}
	if ( zero < 0 )
	{
		int32_t a = m->v[3 * t], b = m->v[3 * t + 1], c = m->v[3 * t + 2];
		int32_t n0 = m->n[3 * t], n1 = m->n[3 * t + 1], n2 = m->n[3 * t + 2];
		uint8_t f0 = m->fixed[3 * t], f1 = m->fixed[3 * t + 1], f2 = m->fixed[3 * t + 2];
		int b0 = n0 >= 0 ? back_edge( m, n0, t ) : -1, b1 = n1 >= 0 ? back_edge( m, n1, t ) : -1;
		int b2 = n2 >= 0 ? back_edge( m, n2, t ) : -1;
		int32_t t1 = add_triangle( m, b, c, i ), t2 = add_triangle( m, c, a, i );
		set_triangle( m, t, ( int32_t[3] ){ a, b, i }, ( int32_t[3] ){ t1, t2, n2 }, ( int[3] ){ -1, -1, b2 },
					  ( uint8_t[3] ){ 0, 0, f2 } );
		set_triangle( m, t1, ( int32_t[3] ){ b, c, i }, ( int32_t[3] ){ t2, t, n0 }, ( int[3] ){ -1, -1, b0 },
					  ( uint8_t[3] ){ 0, 0, f0 } );
		set_triangle( m, t2, ( int32_t[3] ){ c, a, i }, ( int32_t[3] ){ t, t1, n1 }, ( int[3] ){ -1, -1, b1 },
					  ( uint8_t[3] ){ 0, 0, f1 } );
		vt[a] = t, vt[b] = t1, vt[c] = t2, vt[i] = t;
		m->last = t;
		if ( push( m, 3 * t + 2 ) || push( m, 3 * t1 + 2 ) || push( m, 3 * t2 + 2 ) )
		{
			return -1;
		}
		return legalize( m, vt );
	}
	/* On edge `zero` of t (the edge b–c opposite a): split t and its neighbour u into four. */
	int k = zero;
	int32_t u = m->n[3 * t + k];
	int32_t a = m->v[3 * t + k], b = m->v[3 * t + next3( k )], c = m->v[3 * t + prev3( k )];
	uint8_t fs = m->fixed[3 * t + k];
	int32_t n_ab = m->n[3 * t + prev3( k )], n_ca = m->n[3 * t + next3( k )];
	uint8_t f_ab = m->fixed[3 * t + prev3( k )], f_ca = m->fixed[3 * t + next3( k )];
	int bab = n_ab >= 0 ? back_edge( m, n_ab, t ) : -1, bca = n_ca >= 0 ? back_edge( m, n_ca, t ) : -1;
	int j = back_edge( m, u, t );
	int32_t d = m->v[3 * u + j];
	int32_t n_bd = m->n[3 * u + next3( j )], n_dc = m->n[3 * u + prev3( j )];
	uint8_t f_bd = m->fixed[3 * u + next3( j )], f_dc = m->fixed[3 * u + prev3( j )];
	int bbd = n_bd >= 0 ? back_edge( m, n_bd, u ) : -1, bdc = n_dc >= 0 ? back_edge( m, n_dc, u ) : -1;
	int32_t t2 = add_triangle( m, a, i, c ), u2 = add_triangle( m, d, i, b );
	int32_t t1 = t, u1 = u;
	set_triangle( m, t1, ( int32_t[3] ){ a, b, i }, ( int32_t[3] ){ u2, t2, n_ab }, ( int[3] ){ -1, -1, bab },
				  ( uint8_t[3] ){ fs, 0, f_ab } );
	set_triangle( m, t2, ( int32_t[3] ){ a, i, c }, ( int32_t[3] ){ u1, n_ca, t1 }, ( int[3] ){ -1, bca, -1 },
				  ( uint8_t[3] ){ fs, f_ca, 0 } );
	set_triangle( m, u1, ( int32_t[3] ){ d, c, i }, ( int32_t[3] ){ t2, u2, n_dc }, ( int[3] ){ -1, -1, bdc },
				  ( uint8_t[3] ){ fs, 0, f_dc } );
	set_triangle( m, u2, ( int32_t[3] ){ d, i, b }, ( int32_t[3] ){ t1, n_bd, u1 }, ( int[3] ){ -1, bbd, -1 },
				  ( uint8_t[3] ){ fs, f_bd, 0 } );
	vt[a] = t1, vt[b] = t1, vt[c] = t2, vt[d] = u1, vt[i] = t1;
	m->last = t1;
	if ( push( m, 3 * t1 + 2 ) || push( m, 3 * t2 + 1 ) || push( m, 3 * u1 + 2 ) || push( m, 3 * u2 + 1 ) )
	{
		return -1;
	}
	return legalize( m, vt );
}

/* The triangle holding directed edge x → y (y = v[k+1] when x = v[k]), found by turning
 * around x; -1 when x and y are not joined. *kx gets x's corner index. */
static int32_t find_edge( const mesh* m, const int32_t* vt, int32_t x, int32_t y, int* kx )
{
	int32_t start = vt[x], t = start;
	do
	{
		int i = m->v[3 * t] == x ? 0 : ( m->v[3 * t + 1] == x ? 1 : 2 );
		if ( m->v[3 * t + next3( i )] == y )
		{
			*kx = i;
			return t;
		}
		/* Next triangle clockwise around x: across the edge x – v[i+1]. */
		t = m->n[3 * t + prev3( i )];
	} while ( t >= 0 && t != start );
	return -1;
}

static int mark_fixed( mesh* m, const int32_t* vt, int32_t x, int32_t y )
{
	int k;
	int32_t t = find_edge( m, vt, x, y, &k );
	if ( t < 0 )
	{
		t = find_edge( m, vt, y, x, &k );
		if ( t < 0 )
		{
			return 0;
		}
	}
	int e = prev3( k ); /* edge v[k] – v[k+1] is opposite v[k+2] */
	m->fixed[3 * t + e] = 1;
	int32_t u = m->n[3 * t + e];
	if ( u >= 0 )
	{
		m->fixed[3 * u + back_edge( m, u, t )] = 1;
	}
	return 1;
}

typedef struct edge_list
{
	int32_t* e;
	int32_t count, capacity;
} edge_list;

static int edge_push( edge_list* list, int32_t x, int32_t y )
{
	const int32_t edge[2] = { x, y };
	int32_t* e = sere_array_append( list->e, &list->count, &list->capacity, 64, edge, sizeof( edge ) );
	list->e = e != NULL ? e : list->e;
	return e != NULL ? 0 : -1;
}

/* Strictly inside segment a–b (collinear, between the end points). */
static int on_segment( ipoint a, ipoint b, ipoint w )
{
	if ( orient( a, b, w ) != 0 )
	{
		return 0;
	}
	int64_t dot1 = ( w.x - a.x ) * ( b.x - a.x ) + ( w.y - a.y ) * ( b.y - a.y );
	int64_t dot2 = ( w.x - b.x ) * ( a.x - b.x ) + ( w.y - b.y ) * ( a.y - b.y );
	return dot1 > 0 && dot2 > 0;
}

/* Segments x–y and a–b cross at a point interior to both. */
static int crosses( ipoint x, ipoint y, ipoint a, ipoint b )
{
	int64_t o1 = orient( a, b, x ), o2 = orient( a, b, y );
	int64_t o3 = orient( x, y, a ), o4 = orient( x, y, b );
	return ( ( o1 > 0 && o2 < 0 ) || ( o1 < 0 && o2 > 0 ) ) && ( ( o3 > 0 && o4 < 0 ) || ( o3 < 0 && o4 > 0 ) );
}

/* Inserts constrained edge a–b (Sloan's edge flipping). *through gets a vertex lying exactly
 * on the open segment when there is one (the caller splits there), else -1. */
static sere_status insert_segment( mesh* m, int32_t* vt, int32_t a, int32_t b, edge_list* crossing, int32_t* through )
{
	*through = -1;
	int k;
	if ( find_edge( m, vt, a, b, &k ) >= 0 || find_edge( m, vt, b, a, &k ) >= 0 )
	{
		mark_fixed( m, vt, a, b );
		return SERE_OK;
	}
	ipoint pa = m->p[a], pb = m->p[b];
	/* Turn around a to the triangle whose opposite edge the segment leaves through. */
	int32_t start = vt[a], t = start, found = -1;
	do
	{
		int i = m->v[3 * t] == a ? 0 : ( m->v[3 * t + 1] == a ? 1 : 2 );
		int32_t p = m->v[3 * t + next3( i )], q = m->v[3 * t + prev3( i )];
		if ( on_segment( pa, pb, m->p[p] ) )
		{
			*through = p;
			return SERE_OK;
		}
		if ( on_segment( pa, pb, m->p[q] ) )
		{
			*through = q;
			return SERE_OK;
		}
		if ( orient( pa, m->p[p], pb ) > 0 && orient( pa, pb, m->p[q] ) > 0 )
		{
			found = t;
			break;
		}
		t = m->n[3 * t + prev3( i )];
	} while ( t >= 0 && t != start );
	if ( found < 0 )
	{
		return SERE_ERR_GEOMETRY;
	}
	/* Walk along the segment collecting the edges it crosses. */
	crossing->count = 0;
	t = found;
	int i = m->v[3 * t] == a ? 0 : ( m->v[3 * t + 1] == a ? 1 : 2 );
	int32_t p = m->v[3 * t + next3( i )], q = m->v[3 * t + prev3( i )];
	int e = i; /* edge p–q of t, opposite a */
	for ( ;; )
	{
		if ( m->fixed[3 * t + e] )
		{
			return SERE_ERR_GEOMETRY; /* crosses another constrained segment */
		}
		if ( edge_push( crossing, p, q ) != 0 )
		{
			return SERE_ERR_MEMORY;
		}
		int32_t u = m->n[3 * t + e];
		int j = back_edge( m, u, t );
		int32_t w = m->v[3 * u + j];
		if ( w == b )
		{
			break;
		}
		if ( on_segment( pa, pb, m->p[w] ) )
		{
			*through = w;
			return SERE_OK;
		}
		/* u = (w, v1, v2) counter-clockwise with v1–v2 the edge just crossed: the segment
		 * leaves through w–v2 or v1–w. */
		int32_t v2 = m->v[3 * u + prev3( j )];
		e = crosses( m->p[w], m->p[v2], pa, pb ) ? next3( j ) : prev3( j );
		t = u;
		p = m->v[3 * t + next3( e )];
		q = m->v[3 * t + prev3( e )];
	}
	/* Flip crossing edges away; an edge whose quad is not strictly convex waits its turn. */
	int32_t guard = 0;
	int32_t head = 0;
	while ( head < crossing->count )
	{
		int32_t x = crossing->e[2 * head], y = crossing->e[2 * head + 1];
		head += 1;
		int kx;
		int32_t tt = find_edge( m, vt, x, y, &kx );
		if ( tt < 0 )
		{
			return SERE_ERR_GEOMETRY;
		}
		int ee = prev3( kx ); /* tt = (x, y, c): edge x–y is opposite c */
		int32_t uu = m->n[3 * tt + ee];
		int32_t c = m->v[3 * tt + ee];
		int32_t d = m->v[3 * uu + back_edge( m, uu, tt )];
		int64_t ox = orient( m->p[c], m->p[d], m->p[x] ), oy = orient( m->p[c], m->p[d], m->p[y] );
		if ( ( ox > 0 && oy < 0 ) || ( ox < 0 && oy > 0 ) )
		{
			flip( m, tt, ee );
			vt[c] = tt, vt[x] = tt, vt[d] = tt, vt[y] = uu;
			if ( crosses( m->p[c], m->p[d], pa, pb ) && edge_push( crossing, c, d ) != 0 )
			{
				return SERE_ERR_MEMORY;
			}
		}
		else if ( edge_push( crossing, x, y ) != 0 )
		{
			return SERE_ERR_MEMORY;
		}
		if ( ++guard > ( 1 << 26 ) )
		{
			return SERE_ERR_GEOMETRY;
		}
	}
	return mark_fixed( m, vt, a, b ) ? SERE_OK : SERE_ERR_GEOMETRY;
}

static uint64_t spread32( uint64_t v )
{
	v &= 0xffffffffull;
	v = ( v | ( v << 16 ) ) & 0x0000ffff0000ffffull;
	v = ( v | ( v << 8 ) ) & 0x00ff00ff00ff00ffull;
	v = ( v | ( v << 4 ) ) & 0x0f0f0f0f0f0f0f0full;
	v = ( v | ( v << 2 ) ) & 0x3333333333333333ull;
	v = ( v | ( v << 1 ) ) & 0x5555555555555555ull;
	return v;
}

void sere_triangulation_destroy( sere_triangulation* triangulation )
{
	free( triangulation->tri );
	free( triangulation->vertex_map );
	memset( triangulation, 0, sizeof( *triangulation ) );
}

/* The snapping frame: the lower corner of the input's bounding box and the grid cells per unit.
 * Every point must be finite and every segment end an input point. */
static sere_status snap_frame( const sere_cdt_input* input, double* x0, double* y0, double* scale )
{
	const int32_t n = input->point_count;
	double lo_x = INFINITY, lo_y = INFINITY, hi_x = -INFINITY, hi_y = -INFINITY;
	for ( int32_t i = 0; i < n; ++i )
	{
		if ( !isfinite( input->x[i] ) || !isfinite( input->y[i] ) )
		{
			return SERE_ERR_NONFINITE;
		}
		lo_x = fmin( lo_x, input->x[i] ), hi_x = fmax( hi_x, input->x[i] );
		lo_y = fmin( lo_y, input->y[i] ), hi_y = fmax( hi_y, input->y[i] );
	}
	for ( int32_t s = 0; s < 2 * input->segment_count; ++s )
	{
		if ( input->segments[s] < 0 || input->segments[s] >= n )
		{
			return SERE_ERR_ARGUMENT;
		}
	}
	double extent = fmax( hi_x - lo_x, hi_y - lo_y );
	if ( !( extent > 0.0 ) )
	{
		return SERE_ERR_GEOMETRY;
	}
	*x0 = lo_x, *y0 = lo_y;
	*scale = (double) ( ( (int64_t) 1 << GRID_BITS ) - 1 ) / extent;
	return SERE_OK;
}

/* Snaps the points to the grid and inserts them into the super triangle in Morton order, so each
 * insertion starts its walk next to the previous point. Equal keys are equal snapped points: the
 * first in input order represents them (out's vertex_map and merged_count). -1 when out of memory. */
static int insert_points( mesh* m, int32_t* vt, sere_sort_item* order, const sere_cdt_input* input, double x0,
						  double y0, double scale, sere_triangulation* out )
{
	const int32_t n = input->point_count;
	for ( int32_t i = 0; i < n; ++i )
	{
		m->p[i].x = (int64_t) llround( ( input->x[i] - x0 ) * scale );
		m->p[i].y = (int64_t) llround( ( input->y[i] - y0 ) * scale );
		order[i].key = spread32( (uint64_t) m->p[i].x ) | ( spread32( (uint64_t) m->p[i].y ) << 1 );
		order[i].index = i;
		vt[i] = -1;
	}
	sere_sort_items( order, n );
	for ( int32_t k = 0; k < n; ++k )
	{
		int32_t i = order[k].index;
		out->vertex_map[i] = ( k > 0 && order[k].key == order[k - 1].key ) ? out->vertex_map[order[k - 1].index] : i;
		out->merged_count += out->vertex_map[i] != i;
	}
	const int32_t s0 = n, s1 = n + 1, s2 = n + 2;
	m->p[s0] = ( ipoint ){ -SUPER_COORD, -SUPER_COORD };
	m->p[s1] = ( ipoint ){ SUPER_COORD, -SUPER_COORD };
	m->p[s2] = ( ipoint ){ 0, SUPER_COORD };
	m->point_count = n + 3;
	add_triangle( m, s0, s1, s2 );
	vt[s0] = vt[s1] = vt[s2] = 0;
	for ( int32_t k = 0; k < n; ++k )
	{
		int32_t i = order[k].index;
		if ( out->vertex_map[i] == i && insert_point( m, vt, i ) != 0 )
		{
			return -1;
		}
	}
	return 0;
}

/* The outline must be counter-clockwise (positive area) on the snapped grid. */
static int counter_clockwise( const mesh* m, const int32_t* outline, int32_t count )
{
	int128 area2 = 0;
	for ( int32_t i = 0; i < count; ++i )
	{
		ipoint a = m->p[outline[i]], b = m->p[outline[( i + 1 ) % count]];
		area2 += (int128) a.x * b.y - (int128) b.x * a.y;
	}
	return area2 > 0;
}

/* Constraints: the outline's edges, then the vein segments. A segment passing through a point is
 * split there and both halves inserted. */
static sere_status insert_constraints( mesh* m, int32_t* vt, const sere_cdt_input* input, const int32_t* vertex_map,
									   edge_list* crossing )
{
	sere_status status = SERE_OK;
	int32_t total = input->boundary_count + input->segment_count;
	edge_list pending = { 0 };
	for ( int32_t s = total - 1; s >= 0 && status == SERE_OK; --s )
	{
		int32_t a = s < input->boundary_count ? s : input->segments[2 * ( s - input->boundary_count )];
		int32_t b = s < input->boundary_count ? ( s + 1 ) % input->boundary_count
											  : input->segments[2 * ( s - input->boundary_count ) + 1];
		if ( edge_push( &pending, vertex_map[a], vertex_map[b] ) != 0 )
		{
			status = SERE_ERR_MEMORY;
		}
	}
	while ( status == SERE_OK && pending.count > 0 )
	{
		pending.count -= 1;
		int32_t a = pending.e[2 * pending.count], b = pending.e[2 * pending.count + 1];
		if ( a == b )
		{
			continue;
		}
		int32_t through;
		status = insert_segment( m, vt, a, b, crossing, &through );
		if ( status == SERE_OK && through >= 0 &&
			 ( edge_push( &pending, through, b ) != 0 || edge_push( &pending, a, through ) != 0 ) )
		{
			status = SERE_ERR_MEMORY;
		}
	}
	free( pending.e );
	return status;
}

/* Exterior: every triangle reachable from a super corner (a vertex n or past) without crossing a
 * constraint. -1 when out of memory. */
static int mark_exterior( mesh* m, int32_t n, uint8_t* exterior )
{
	m->stack_count = 0;
	for ( int32_t t = 0; t < m->count; ++t )
	{
		if ( m->v[3 * t] >= n || m->v[3 * t + 1] >= n || m->v[3 * t + 2] >= n )
		{
			exterior[t] = 1;
			if ( push( m, t ) != 0 )
			{
				return -1;
			}
		}
	}
	while ( m->stack_count > 0 )
	{
		int32_t t = m->stack[--m->stack_count];
		for ( int k = 0; k < 3; ++k )
		{
			int32_t u = m->n[3 * t + k];
			if ( u >= 0 && !exterior[u] && !m->fixed[3 * t + k] )
			{
				exterior[u] = 1;
				if ( push( m, u ) != 0 )
				{
					return -1;
				}
			}
		}
	}
	return 0;
}

/* A boundary edge with the domain on both sides or neither means the outline touches itself; a
 * vein segment outside the outline shows up as a constrained edge between two exterior
 * triangles. */
static int constraints_bound_domain( const mesh* m, const uint8_t* exterior )
{
	for ( int32_t t = 0; t < m->count; ++t )
	{
		for ( int k = 0; k < 3; ++k )
		{
			int32_t u = m->n[3 * t + k];
			if ( m->fixed[3 * t + k] && exterior[t] && ( u < 0 || exterior[u] ) )
			{
				return 0;
			}
		}
	}
	return 1;
}

/* Restore the Delaunay property on every unconstrained interior edge: Lawson's flips terminate,
 * and locally Delaunay everywhere means constrained Delaunay. -1 when out of memory. */
static int restore_delaunay( mesh* m, int32_t* vt, const uint8_t* exterior )
{
	m->stack_count = 0;
	for ( int32_t t = 0; t < m->count; ++t )
	{
		for ( int k = 0; !exterior[t] && k < 3; ++k )
		{
			if ( push( m, 3 * t + k ) != 0 )
			{
				return -1;
			}
		}
	}
	while ( m->stack_count > 0 )
	{
		int32_t code = m->stack[--m->stack_count];
		int32_t t = code / 3;
		int k = code % 3;
		int32_t u = m->n[3 * t + k];
		if ( u < 0 || m->fixed[3 * t + k] || exterior[t] || exterior[u] )
		{
			continue;
		}
		int j = back_edge( m, u, t );
		int32_t a = m->v[3 * t + k], b = m->v[3 * t + next3( k )], c = m->v[3 * t + prev3( k )], d = m->v[3 * u + j];
		if ( incircle( m->p[a], m->p[b], m->p[c], m->p[d] ) <= 0 )
		{
			continue;
		}
		flip( m, t, k );
		vt[a] = t, vt[b] = t, vt[d] = t, vt[c] = u;
		for ( int q = 0; q < 3; ++q )
		{
			if ( push( m, 3 * t + q ) != 0 || push( m, 3 * u + q ) != 0 )
			{
				return -1;
			}
		}
	}
	return 0;
}

/* The interior triangles, in mesh order, into out->tri. */
static sere_status copy_interior( const mesh* m, const uint8_t* exterior, sere_triangulation* out )
{
	int32_t inside = 0;
	for ( int32_t t = 0; t < m->count; ++t )
	{
		inside += !exterior[t];
	}
	out->tri = malloc( sizeof( int32_t ) * 3 * (size_t) ( inside > 0 ? inside : 1 ) );
	if ( out->tri == NULL )
	{
		return SERE_ERR_MEMORY;
	}
	for ( int32_t t = 0; t < m->count; ++t )
	{
		if ( !exterior[t] )
		{
			memcpy( out->tri + 3 * out->triangle_count, m->v + 3 * t, sizeof( int32_t ) * 3 );
			out->triangle_count += 1;
		}
	}
	return SERE_OK;
}

sere_status sere_triangulate( const sere_cdt_input* input, sere_triangulation* out )
{
	memset( out, 0, sizeof( *out ) );
	if ( input == NULL || input->x == NULL || input->y == NULL || input->point_count < 3 || input->boundary_count < 3 ||
		 input->boundary_count > input->point_count || input->segment_count < 0 ||
		 ( input->segment_count > 0 && input->segments == NULL ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	double x0, y0, scale;
	sere_status status = snap_frame( input, &x0, &y0, &scale );
	if ( status != SERE_OK )
	{
		return status;
	}
	const int32_t n = input->point_count;
	mesh m = { 0 };
	edge_list crossing = { 0 };
	uint8_t* exterior = NULL;
	sere_sort_item* order = malloc( sizeof( sere_sort_item ) * (size_t) n );
	m.p = malloc( sizeof( ipoint ) * ( (size_t) n + 3 ) );
	int32_t* vt = malloc( sizeof( int32_t ) * ( (size_t) n + 3 ) );
	out->vertex_map = malloc( sizeof( int32_t ) * (size_t) n );
	if ( order == NULL || m.p == NULL || vt == NULL || out->vertex_map == NULL || grow( &m, 2 * n + 8 ) != 0 ||
		 insert_points( &m, vt, order, input, x0, y0, scale, out ) != 0 )
	{
		status = SERE_ERR_MEMORY;
		goto done;
	}
	if ( !counter_clockwise( &m, out->vertex_map, input->boundary_count ) )
	{
		status = SERE_ERR_GEOMETRY;
		goto done;
	}
	status = insert_constraints( &m, vt, input, out->vertex_map, &crossing );
	if ( status != SERE_OK )
	{
		goto done;
	}
	exterior = calloc( (size_t) m.count, 1 );
	if ( exterior == NULL || mark_exterior( &m, n, exterior ) != 0 )
	{
		status = SERE_ERR_MEMORY;
		goto done;
	}
	if ( !constraints_bound_domain( &m, exterior ) )
	{
		status = SERE_ERR_GEOMETRY;
		goto done;
	}
	if ( restore_delaunay( &m, vt, exterior ) != 0 )
	{
		status = SERE_ERR_MEMORY;
		goto done;
	}
	status = copy_interior( &m, exterior, out );

done:
	free( order );
	free( m.p );
	free( m.v );
	free( m.n );
	free( m.fixed );
	free( m.stack );
	free( crossing.e );
	free( vt );
	free( exterior );
	if ( status != SERE_OK )
	{
		sere_triangulation_destroy( out );
	}
	return status;
}

static double angle_at( double ax, double ay, double bx, double by, double cx, double cy )
{
	double ux = bx - ax, uy = by - ay, vx = cx - ax, vy = cy - ay;
	return atan2( fabs( ux * vy - uy * vx ), ux * vx + uy * vy );
}

void sere_mesh_quality_measure( const double* x, const double* y, const int32_t* tri, int32_t triangle_count,
								const uint8_t* constrained_vertex, sere_mesh_quality* quality )
{
	const double degrees = 57.295779513082320876798;
	quality->min_angle_deg = 180.0;
	quality->min_angle_free_deg = 180.0;
	quality->max_aspect = 0.0;
	quality->inverted = 0;
	quality->free_triangle_count = 0;
	for ( int32_t t = 0; t < triangle_count; ++t )
	{
		const int32_t* v = tri + 3 * t;
		double ax = x[v[0]], ay = y[v[0]], bx = x[v[1]], by = y[v[1]], cx = x[v[2]], cy = y[v[2]];
		double area2 = ( bx - ax ) * ( cy - ay ) - ( cx - ax ) * ( by - ay );
		if ( !( area2 > 0.0 ) )
		{
			quality->inverted += 1;
			continue;
		}
		double angle = fmin( angle_at( ax, ay, bx, by, cx, cy ),
							 fmin( angle_at( bx, by, cx, cy, ax, ay ), angle_at( cx, cy, ax, ay, bx, by ) ) );
		double la = hypot( bx - cx, by - cy ), lb = hypot( cx - ax, cy - ay ), lc = hypot( ax - bx, ay - by );
		/* inradius r = area / semi-perimeter; an equilateral triangle has longest / (2√3 r) = 1 */
		double r = 0.5 * area2 / ( 0.5 * ( la + lb + lc ) );
		double aspect = fmax( la, fmax( lb, lc ) ) / ( 2.0 * sqrt( 3.0 ) * r );
		quality->min_angle_deg = fmin( quality->min_angle_deg, angle * degrees );
		quality->max_aspect = fmax( quality->max_aspect, aspect );
		int is_free = constrained_vertex == NULL ||
					  ( !constrained_vertex[v[0]] && !constrained_vertex[v[1]] && !constrained_vertex[v[2]] );
		if ( is_free )
		{
			quality->free_triangle_count += 1;
			quality->min_angle_free_deg = fmin( quality->min_angle_free_deg, angle * degrees );
		}
	}
}
