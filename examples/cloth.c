/* A cloth hanging from two corners, with sere's constraint coloring (color.h) and colored
 * Gauss–Seidel position-based dynamics (pbd.h): the start of a PBD solver.
 *
 * An N×N grid of particles joined by structural (edge) and shear (diagonal) distance
 * constraints starts horizontal, folded like an accordion so that its top edge has slack; the two
 * corners of that edge are pinned (inverse mass 0) and gravity pulls the cloth down along −z for
 * a second of simulated time. The program checks
 *   - the coloring: every constraint has one color, the colors partition the constraints, and no
 *     two constraints of a color share a particle (so a batch can be projected in parallel);
 *   - every frame's projection converged (max |C/l| below the tolerance, measured here again on
 *     the positions it returned, not only taken from its report);
 *   - the pinned corners stayed where they were and the cloth fell (it hangs below its start);
 * and exits non-zero when a check fails.
 *
 *   cc cloth.c $(pkg-config --cflags --libs sere) -o cloth && ./cloth */
#include <sere.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#define N		   16	 /* particles per side */
#define SPACING	   0.04f /* rest distance between neighbours (m) */
#define FRAMES	   120	 /* 1 s at 120 frames per second */
#define TOLERANCE  1e-3f /* λ_C: stop when max |C/l| is below it */
#define MAX_SWEEPS 20000 /* the cap a frame must not reach */
#define THREADS	   2	 /* for every kernel call, said at the call (0: OpenMP's count) */

/* Appends the constraint (p, q) with its rest length. */
static void add( int32_t* a, int32_t* b, float* rest, int32_t* count, int32_t p, int32_t q, float length )
{
	a[*count] = p;
	b[*count] = q;
	rest[*count] = length;
	++*count;
}

/* 0 when the coloring partitions the constraints into batches of which no two share a
 * particle; else prints what is wrong and returns 1. */
static int check_coloring( const sere_coloring* coloring, const int32_t* a, const int32_t* b, int32_t count,
						   int32_t particles, const char* name )
{
	int32_t* seen = calloc( (size_t) count, sizeof( int32_t ) );
	int32_t* owner = malloc( sizeof( int32_t ) * (size_t) particles ); /* last color touching a particle */
	if ( seen == NULL || owner == NULL )
	{
		fprintf( stderr, "cloth: out of memory\n" );
		return 1;
	}
	for ( int32_t p = 0; p < particles; ++p )
	{
		owner[p] = -1;
	}
	int bad = coloring->color_count < 1 || coloring->color_count > SERE_MAX_COLORS || coloring->offsets[0] != 0 ||
			  coloring->offsets[coloring->color_count] != count;
	for ( int32_t c = 0; c < coloring->color_count && !bad; ++c )
	{
		for ( int32_t k = coloring->offsets[c]; k < coloring->offsets[c + 1] && !bad; ++k )
		{
			const int32_t s = coloring->order[k];
			if ( s < 0 || s >= count || seen[s]++ || coloring->color[s] != c )
			{
				fprintf( stderr, "cloth: FAIL %s: constraint %d is listed wrongly in color %d\n", name, s, c );
				bad = 1;
			}
			else if ( owner[a[s]] == c || owner[b[s]] == c )
			{
				fprintf( stderr, "cloth: FAIL %s: color %d has two constraints on particle %d\n", name, c,
						 owner[a[s]] == c ? a[s] : b[s] );
				bad = 1;
			}
			else
			{
				owner[a[s]] = owner[b[s]] = c;
			}
		}
	}
	free( seen );
	free( owner );
	return bad;
}

/* The cloth's particles and arrays (sere's arrays start on a cache line and are padded to
 * SERE_PAD entries, base.h). */
typedef struct cloth
{
	int32_t n, count;
	float *x, *y, *z, *vx, *vy, *vz, *px, *py, *pz, *inv_m, *rest;
	int32_t *a, *b;
	int32_t pinned[2];
	float pin_x[2], pin_y[2], pin_z[2];
} cloth;

static void cloth_free( cloth* c )
{
	sere_free( c->x ), sere_free( c->y ), sere_free( c->z ), sere_free( c->vx ), sere_free( c->vy ), sere_free( c->vz );
	sere_free( c->px ), sere_free( c->py ), sere_free( c->pz ), sere_free( c->inv_m ), sere_free( c->a );
	sere_free( c->b ), sere_free( c->rest );
}

/* The folded grid, its two pinned corners and its constraints; 1 when out of memory. */
static int cloth_make( cloth* c )
{
	const int32_t n = N * N;
	const int32_t capacity = 4 * n; /* (N−1)·N·2 structural + (N−1)²·2 shear < 4 N² */
	const size_t fbytes = sizeof( float ) * (size_t) sere_pad( n );
	*c = ( cloth ){ .n = n };
	c->x = sere_alloc( fbytes ), c->y = sere_alloc( fbytes ), c->z = sere_alloc( fbytes );
	c->vx = sere_alloc( fbytes ), c->vy = sere_alloc( fbytes ), c->vz = sere_alloc( fbytes );
	c->px = sere_alloc( fbytes ), c->py = sere_alloc( fbytes ), c->pz = sere_alloc( fbytes );
	c->inv_m = sere_alloc( fbytes );
	c->a = sere_alloc( sizeof( int32_t ) * (size_t) capacity );
	c->b = sere_alloc( sizeof( int32_t ) * (size_t) capacity );
	c->rest = sere_alloc( sizeof( float ) * (size_t) capacity );
	if ( !c->x || !c->y || !c->z || !c->vx || !c->vy || !c->vz || !c->px || !c->py || !c->pz || !c->inv_m || !c->a ||
		 !c->b || !c->rest )
	{
		fprintf( stderr, "cloth: out of memory\n" );
		return 1;
	}
	for ( int32_t i = 0; i < N; ++i ) /* row i, from the top edge (y = 0) down */
	{
		for ( int32_t j = 0; j < N; ++j )
		{
			const int32_t p = i * N + j;
			/* folded like an accordion along the columns: 0.8 of the width, every constraint at
			 * its rest length (0.8² + 0.6² = 1), so the top edge has slack to sag */
			c->x[p] = 0.8f * j * SPACING;
			c->y[p] = -i * SPACING;
			c->z[p] = ( j % 2 ? -0.3f : 0.3f ) * SPACING;
			c->inv_m[p] = 1.0f;
		}
	}
	c->pinned[0] = 0, c->pinned[1] = N - 1; /* the top edge's two corners */
	for ( int k = 0; k < 2; ++k )
	{
		const int32_t p = c->pinned[k];
		c->inv_m[p] = 0.0f;
		c->pin_x[k] = c->x[p], c->pin_y[k] = c->y[p], c->pin_z[k] = c->z[p];
	}

	/* rest lengths: the flat cloth's (SPACING, and SPACING·√2 for the shear diagonals) */
	for ( int32_t i = 0; i < N; ++i )
	{
		for ( int32_t j = 0; j < N; ++j )
		{
			const int32_t p = i * N + j;
			if ( j + 1 < N )
			{
				add( c->a, c->b, c->rest, &c->count, p, p + 1, SPACING );
			}
			if ( i + 1 < N )
			{
				add( c->a, c->b, c->rest, &c->count, p, p + N, SPACING );
			}
			if ( i + 1 < N && j + 1 < N )
			{
				add( c->a, c->b, c->rest, &c->count, p, p + N + 1, SPACING * sqrtf( 2.0f ) );
			}
		}
	}
	return 0;
}

/* max |C/l| measured on the cloth's positions, not taken from a report */
static float cloth_strain( const cloth* c )
{
	float strain = 0.0f;
	for ( int32_t s = 0; s < c->count; ++s )
	{
		const int32_t a = c->a[s], b = c->b[s];
		const float dx = c->x[a] - c->x[b], dy = c->y[a] - c->y[b], dz = c->z[a] - c->z[b];
		strain = fmaxf( strain, fabsf( sqrtf( dx * dx + dy * dy + dz * dz ) - c->rest[s] ) / c->rest[s] );
	}
	return strain;
}

/* FRAMES frames under gravity; 1 when a frame fails to converge or its measured strain is above
 * the tolerance. */
static int cloth_fall( cloth* c, sere_pbd* pbd )
{
	sere_pbd_params params = sere_pbd_params_default();
	params.tolerance = TOLERANCE;
	params.max_iterations = MAX_SWEEPS;
	params.dt = 1.0f / FRAMES;
	const float gravity[3] = { 0.0f, 0.0f, -9.81f };
	int32_t most_sweeps = 0, total_sweeps = 0;
	float worst = 0.0f;
	for ( int32_t frame = 0; frame < FRAMES; ++frame )
	{
		sere_pbd_predict( c->n, c->x, c->y, c->z, c->vx, c->vy, c->vz, c->px, c->py, c->pz, c->inv_m, gravity,
						  params.dt, THREADS );
		sere_pbd_report report = { 0 };
		sere_status status = sere_pbd_project( pbd, c->px, c->py, c->pz, c->inv_m, &params, &report );
		if ( status != SERE_OK || report.hit_cap || !( report.max_strain < TOLERANCE ) )
		{
			fprintf( stderr, "cloth: FAIL frame %d: %s, %d sweeps, max |C/l| %g\n", frame, sere_status_text( status ),
					 report.iterations, report.max_strain );
			return 1;
		}
		sere_pbd_finish( c->n, c->x, c->y, c->z, c->vx, c->vy, c->vz, c->px, c->py, c->pz, params.dt, THREADS );
		const float strain = cloth_strain( c );
		if ( !( strain < TOLERANCE ) )
		{
			fprintf( stderr, "cloth: FAIL frame %d: measured max |C/l| %g, reported %g\n", frame, strain,
					 report.max_strain );
			return 1;
		}
		worst = fmaxf( worst, strain );
		most_sweeps = report.iterations > most_sweeps ? report.iterations : most_sweeps;
		total_sweeps += report.iterations;
	}
	printf( "cloth: %d frames, %d sweeps per frame on average, at most %d; worst max |C/l| %.6e < %g\n", FRAMES,
			total_sweeps / FRAMES, most_sweeps, worst, TOLERANCE );
	return 0;
}

/* 1 unless the pinned corners stayed put and the cloth fell by a good part of its length */
static int cloth_check_hang( const cloth* c )
{
	int failed = 0;
	float lowest = 0.0f;
	for ( int32_t p = 0; p < c->n; ++p )
	{
		lowest = fminf( lowest, c->z[p] );
	}
	for ( int k = 0; k < 2; ++k )
	{
		const int32_t p = c->pinned[k];
		if ( c->x[p] != c->pin_x[k] || c->y[p] != c->pin_y[k] || c->z[p] != c->pin_z[k] )
		{
			fprintf( stderr, "cloth: FAIL pinned corner %d moved to (%g, %g, %g)\n", p, c->x[p], c->y[p], c->z[p] );
			failed = 1;
		}
	}
	const float length = ( N - 1 ) * SPACING;
	if ( !( lowest < -0.5f * length ) )
	{
		fprintf( stderr, "cloth: FAIL the cloth did not fall (lowest z %g, length %g)\n", lowest, length );
		failed = 1;
	}
	printf( "cloth: lowest point %.3f m below the pins (cloth %.2f m long)\n", -lowest, length );
	return failed;
}

int main( void )
{
	cloth c;
	if ( cloth_make( &c ) )
	{
		cloth_free( &c );
		return 1;
	}

	/* Coloring on its own (what a solver with its own projection would use) ... */
	sere_coloring coloring = { 0 };
	sere_status status = sere_coloring_create( c.a, c.b, c.count, c.n, &coloring );
	if ( status != SERE_OK )
	{
		fprintf( stderr, "cloth: FAIL coloring: %s\n", sere_status_text( status ) );
		cloth_free( &c );
		return 1;
	}
	int failed = check_coloring( &coloring, c.a, c.b, c.count, c.n, "sere_coloring_create" );
	printf( "cloth: sere %s (%s), %d particles, %d constraints in %d colors of %d-%d\n", sere_version(),
			sere_simd_path(), c.n, c.count, coloring.color_count, coloring.min_batch, coloring.max_batch );

	/* ... and the PBD workspace, which colors the constraints the same way for its sweeps. */
	sere_pbd* pbd = NULL;
	status = sere_pbd_create( c.a, c.b, c.count, c.n, &pbd );
	if ( status == SERE_OK )
	{
		status = sere_pbd_set_threads( pbd, THREADS );
	}
	if ( status == SERE_OK )
	{
		status = sere_pbd_set_rest( pbd, c.rest );
	}
	if ( status != SERE_OK )
	{
		fprintf( stderr, "cloth: FAIL pbd: %s\n", sere_status_text( status ) );
		failed = 1;
	}
	else
	{
		failed |= check_coloring( sere_pbd_coloring( pbd ), c.a, c.b, c.count, c.n, "sere_pbd_create" );
		failed = failed || cloth_fall( &c, pbd ) || cloth_check_hang( &c );
	}
	sere_pbd_destroy( pbd );
	sere_coloring_destroy( &coloring );
	cloth_free( &c );
	puts( failed ? "cloth: FAILED" : "cloth: ok" );
	return failed;
}
