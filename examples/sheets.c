/* Two triangle sheets in contact, with sere's BVH (bvh.h) and self-collision pass (collide.h):
 * the start of a collision stage for any triangle mesh.
 *
 * Two square sheets of M×M vertices (two triangles per cell) lie one above the other, a third
 * of the collision thickness apart and shifted by half a cell, so every vertex hangs over the
 * inside of a triangle of the other sheet. Both sheets are one mesh (one BVH): the collision
 * pass finds vertex–triangle pairs closer than the thickness that are not neighbours in the
 * mesh, which here are exactly the pairs between the sheets, and pushes them apart. The program
 * checks
 *   - the contacts found are what a brute-force search over every vertex–triangle pair finds
 *     (same count, every reported distance below the thickness);
 *   - after the pass no contact is left unresolved, and brute force agrees: every vertex is at
 *     least the thickness (less the solver's tolerance) from every triangle of the other sheet;
 *   - the sheets separated symmetrically (equal masses: the gap's middle stays put);
 * and exits non-zero when a check fails.
 *
 *   cc sheets.c $(pkg-config --cflags --libs sere) -o sheets && ./sheets */
#include <sere.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#define M		  24				/* vertices per side of each sheet */
#define CELL	  0.04f				/* cell size */
#define THICKNESS 0.01f				/* contact when a vertex is closer than this to a triangle */
#define GAP		  ( THICKNESS / 3 ) /* the sheets start this far apart */
#define THREADS	  2					/* for every kernel call, said at the call (0: OpenMP's count) */

/* Brute force over every vertex of one sheet and every triangle of the other: the number of
 * pairs closer than `below` and the smallest distance. */
static int32_t brute_force( const float* x, const float* y, const float* z, const int32_t* tri, int32_t per_sheet,
							int32_t tris_per_sheet, float below, float* closest )
{
	int32_t pairs = 0;
	*closest = INFINITY;
	for ( int32_t v = 0; v < 2 * per_sheet; ++v )
	{
		const int32_t other = v < per_sheet ? 1 : 0; /* the sheet v is not in */
		const float p[3] = { x[v], y[v], z[v] };
		for ( int32_t t = other * tris_per_sheet; t < ( other + 1 ) * tris_per_sheet; ++t )
		{
			const int32_t* c = tri + 3 * t;
			const float a[3] = { x[c[0]], y[c[0]], z[c[0]] }, b[3] = { x[c[1]], y[c[1]], z[c[1]] };
			const float d[3] = { x[c[2]], y[c[2]], z[c[2]] };
			float weights[3];
			const float distance = sqrtf( sere_closest_point_triangle( p, a, b, d, weights ) );
			pairs += distance < below;
			*closest = fminf( *closest, distance );
		}
	}
	return pairs;
}

/* The two sheets: positions, velocities, inverse masses and triangles. */
typedef struct sheets
{
	float *x, *y, *z, *vx, *vy, *vz, *inv_m;
	int32_t* tri;
} sheets;

enum
{
	PER_SHEET = M * M,
	VERTICES = 2 * PER_SHEET,
	TRIS_PER_SHEET = 2 * ( M - 1 ) * ( M - 1 ),
	TRIANGLES = 2 * TRIS_PER_SHEET
};

static void sheets_free( sheets* s )
{
	sere_free( s->x ), sere_free( s->y ), sere_free( s->z ), sere_free( s->vx ), sere_free( s->vy ), sere_free( s->vz );
	sere_free( s->inv_m ), sere_free( s->tri );
}

/* Sheet 0 at z = 0; sheet 1 at z = GAP, shifted by half a cell in x and y. Vertices are
 * numbered row by row, which keeps neighbours close in the numbering: the detection queries
 * eight consecutive vertices together, so a solver should number them in a spatially coherent
 * order (sere's leaves use Morton order). 1 when out of memory. */
static int sheets_make( sheets* s )
{
	const size_t fbytes = sizeof( float ) * (size_t) sere_pad( VERTICES );
	s->x = sere_alloc( fbytes ), s->y = sere_alloc( fbytes ), s->z = sere_alloc( fbytes );
	s->vx = sere_alloc( fbytes ), s->vy = sere_alloc( fbytes ), s->vz = sere_alloc( fbytes );
	s->inv_m = sere_alloc( fbytes );
	s->tri = sere_alloc( sizeof( int32_t ) * 3 * (size_t) TRIANGLES );
	if ( !s->x || !s->y || !s->z || !s->vx || !s->vy || !s->vz || !s->inv_m || !s->tri )
	{
		fprintf( stderr, "sheets: out of memory\n" );
		return 1;
	}
	int32_t t = 0;
	for ( int32_t sheet = 0; sheet < 2; ++sheet )
	{
		const int32_t base = sheet * PER_SHEET;
		for ( int32_t i = 0; i < M; ++i )
		{
			for ( int32_t j = 0; j < M; ++j )
			{
				const int32_t v = base + i * M + j;
				s->x[v] = j * CELL + sheet * 0.5f * CELL;
				s->y[v] = i * CELL + sheet * 0.5f * CELL;
				s->z[v] = sheet * GAP;
				s->vx[v] = s->vy[v] = s->vz[v] = 0.0f;
				s->inv_m[v] = 1.0f;
				if ( i + 1 < M && j + 1 < M ) /* counter-clockwise seen from +z */
				{
					const int32_t c[4] = { v, v + 1, v + M + 1, v + M };
					int32_t* out = s->tri + 3 * t;
					out[0] = c[0], out[1] = c[1], out[2] = c[2], out[3] = c[0], out[4] = c[2], out[5] = c[3];
					t += 2;
				}
			}
		}
	}
	return 0;
}

/* The detection's contacts against brute force: 1 when they disagree. */
static int check_detection( const sheets* s, const sere_collide* collide, int32_t found )
{
	float closest = 0.0f;
	const int32_t expected = brute_force( s->x, s->y, s->z, s->tri, PER_SHEET, TRIS_PER_SHEET, THICKNESS, &closest );
	int32_t count = 0;
	const sere_contact* contacts = sere_collide_contacts( collide, &count );
	float farthest = 0.0f;
	for ( int32_t k = 0; k < count; ++k )
	{
		const int32_t v = contacts[k].vertex, sheet_of_triangle = contacts[k].triangle >= TRIS_PER_SHEET;
		farthest = fmaxf( farthest, contacts[k].distance );
		if ( ( v >= PER_SHEET ) == sheet_of_triangle )
		{
			fprintf( stderr, "sheets: FAIL contact %d joins vertex %d to triangle %d of its own sheet\n", k, v,
					 contacts[k].triangle );
			return 1;
		}
	}
	printf( "sheets: detection found %d contacts (brute force: %d), closest %.4f, farthest %.4f, thickness %.4f\n",
			count, expected, closest, farthest, THICKNESS );
	if ( count != found || count != expected || count == 0 || !( farthest < THICKNESS ) )
	{
		fprintf( stderr, "sheets: FAIL detection disagrees with brute force\n" );
		return 1;
	}
	return 0;
}

/* The pass: refit, then detect and respond, a few rounds to catch contacts the push-out itself
 * makes; 1 when a contact is left or the pair's centre moved. */
static int check_resolve( sheets* s, sere_collide* collide, sere_bvh* bvh )
{
	sere_collide_params params = sere_collide_params_default();
	params.thickness = THICKNESS;
	params.dt = 1.0f / 60;
	params.iterations = 32;
	params.rounds = 4;
	const sere_collide_state state = {
		.x = s->x, .y = s->y, .z = s->z, .vx = s->vx, .vy = s->vy, .vz = s->vz, .inv_m = s->inv_m
	};
	sere_collide_stats stats = { 0 };
	sere_status status = sere_collide_resolve( collide, bvh, &state, &params, &stats );
	if ( status != SERE_OK )
	{
		fprintf( stderr, "sheets: FAIL resolve: %s\n", sere_status_text( status ) );
		return 1;
	}
	const float slack = 2 * SERE_COLLIDE_TOLERANCE * THICKNESS; /* what the solver may leave */
	float closest = 0.0f;
	const int32_t left =
		brute_force( s->x, s->y, s->z, s->tri, PER_SHEET, TRIS_PER_SHEET, THICKNESS - slack, &closest );
	double middle = 0.0;
	for ( int32_t v = 0; v < VERTICES; ++v )
	{
		middle += s->z[v];
	}
	middle /= VERTICES;
	printf( "sheets: %d rounds, %d response iterations, %d unresolved; brute force: %d pairs closer than %.4f, "
			"closest %.5f\n",
			stats.rounds, stats.iterations, stats.unresolved, left, THICKNESS - slack, closest );
	printf( "sheets: mean height %.6f (was %.6f)\n", middle, GAP / 2 );
	int failed = 0;
	if ( stats.unresolved != 0 || left != 0 || !( closest >= THICKNESS - slack ) )
	{
		fprintf( stderr, "sheets: FAIL contacts left after the pass\n" );
		failed = 1;
	}
	if ( !( fabs( middle - GAP / 2 ) < 1e-3 * THICKNESS ) )
	{
		fprintf( stderr, "sheets: FAIL the pass moved the pair's centre (mean height %g)\n", middle );
		failed = 1;
	}
	return failed;
}

int main( void )
{
	sheets s = { 0 };
	if ( sheets_make( &s ) )
	{
		sheets_free( &s );
		return 1;
	}
	sere_bvh* bvh = NULL;
	sere_collide* collide = NULL;
	sere_status status = sere_bvh_create( s.tri, TRIANGLES, VERTICES, s.x, s.y, s.z, &bvh );
	if ( status == SERE_OK )
	{
		status = sere_collide_create( bvh, 0, &collide );
	}
	if ( status == SERE_OK )
	{
		status = sere_collide_set_threads( collide, THREADS );
	}
	int32_t found = 0;
	if ( status == SERE_OK )
	{
		status = sere_collide_detect( collide, bvh, s.x, s.y, s.z, THICKNESS, &found );
	}
	int failed = status != SERE_OK;
	if ( failed )
	{
		fprintf( stderr, "sheets: FAIL %s\n", sere_status_text( status ) );
	}
	else
	{
		printf( "sheets: sere %s (%s), 2 sheets of %d vertices and %d triangles, BVH depth %d\n", sere_version(),
				sere_simd_path(), PER_SHEET, TRIS_PER_SHEET, sere_bvh_depth( bvh ) );
		failed |= check_detection( &s, collide, found );
		failed |= check_resolve( &s, collide, bvh );
	}
	sere_collide_destroy( collide );
	sere_bvh_destroy( bvh );
	sheets_free( &s );
	puts( failed ? "sheets: FAILED" : "sheets: ok" );
	return failed;
}
