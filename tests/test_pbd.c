/* Colored PBD (Sec. 5.2, Jeong Eq. 13) on meshes built here: a cloth patch (structural and shear
 * springs) and a small triangle–Voronoi double layer, so the kernel is tested alone. */
#include "ref/pbd_ref.h"
#include "solve/pbd.h"

#include <criterion/criterion.h>
#include <float.h>
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

typedef struct test_mesh
{
	int32_t n, count;
	float *x, *y, *z, *inv_m;
	int32_t *a, *b;
	float* rest;
	int* kind;	/* 0: T (or cloth), 1: V, 2: L */
	int* rim;	/* per particle: on the outline of the triangle layer */
	int32_t nt; /* triangle-layer particles (the rest are Voronoi particles) */
} test_mesh;

static void mesh_alloc( test_mesh* m, int32_t n, int32_t count )
{
	m->n = n;
	m->count = 0;
	m->x = calloc( (size_t) n, sizeof( float ) );
	m->y = calloc( (size_t) n, sizeof( float ) );
	m->z = calloc( (size_t) n, sizeof( float ) );
	m->inv_m = calloc( (size_t) n, sizeof( float ) );
	m->rim = calloc( (size_t) n, sizeof( int ) );
	m->a = calloc( (size_t) count, sizeof( int32_t ) );
	m->b = calloc( (size_t) count, sizeof( int32_t ) );
	m->rest = calloc( (size_t) count, sizeof( float ) );
	m->kind = calloc( (size_t) count, sizeof( int ) );
}

static void mesh_free( test_mesh* m )
{
	free( m->x ), free( m->y ), free( m->z ), free( m->inv_m ), free( m->rim );
	free( m->a ), free( m->b ), free( m->rest ), free( m->kind );
}

static float distance( const test_mesh* m, int32_t i, int32_t j )
{
	float dx = m->x[j] - m->x[i], dy = m->y[j] - m->y[i], dz = m->z[j] - m->z[i];
	return sqrtf( dx * dx + dy * dy + dz * dz );
}

static void add_spring( test_mesh* m, int32_t i, int32_t j, int kind )
{
	m->a[m->count] = i;
	m->b[m->count] = j;
	m->rest[m->count] = distance( m, i, j );
	m->kind[m->count] = kind;
	m->count += 1;
}

/* nx × ny grid vertices, spacing h, structural (horizontal, vertical) and shear (both
 * diagonals) springs at their rest lengths. */
static void cloth( test_mesh* m, int32_t nx, int32_t ny, float h )
{
	mesh_alloc( m, nx * ny, 4 * nx * ny );
	m->nt = nx * ny;
	for ( int32_t j = 0; j < ny; ++j )
	{
		for ( int32_t i = 0; i < nx; ++i )
		{
			int32_t v = j * nx + i;
			m->x[v] = h * (float) i;
			m->y[v] = h * (float) j;
			m->inv_m[v] = 1.0f;
			m->rim[v] = i == 0 || j == 0 || i == nx - 1 || j == ny - 1;
		}
	}
	for ( int32_t j = 0; j < ny; ++j )
	{
		for ( int32_t i = 0; i < nx; ++i )
		{
			int32_t v = j * nx + i;
			if ( i + 1 < nx )
			{
				add_spring( m, v, v + 1, 0 );
			}
			if ( j + 1 < ny )
			{
				add_spring( m, v, v + nx, 0 );
			}
			if ( i + 1 < nx && j + 1 < ny )
			{
				add_spring( m, v, v + nx + 1, 0 );
				add_spring( m, v + 1, v + nx, 0 );
			}
		}
	}
}

/* The triangle–Voronoi double layer (Sec. 3.2) on an nx × ny cell grid, each cell cut into
 * two triangles: a Voronoi particle per triangle at its centroid + (0, 0, h); T springs on
 * triangle edges, V springs between the Voronoi particles of triangles sharing an edge, three
 * L springs per triangle. Interior vertices jittered by a fixed pattern. */
static void double_layer( test_mesh* m, int32_t nx, int32_t ny, float spacing, float h, float jitter )
{
	const int32_t nt = ( nx + 1 ) * ( ny + 1 ), f = 2 * nx * ny;
	mesh_alloc( m, nt + f, 3 * nt + 5 * f ); /* T ≤ 3N, V ≤ 1.5F, L = 3F */
	m->nt = nt;
	for ( int32_t j = 0; j <= ny; ++j )
	{
		for ( int32_t i = 0; i <= nx; ++i )
		{
			int32_t v = j * ( nx + 1 ) + i;
			int rim = i == 0 || j == 0 || i == nx || j == ny;
			float jx = rim ? 0.0f : jitter * spacing * sinf( 12.9898f * (float) v );
			float jy = rim ? 0.0f : jitter * spacing * cosf( 78.233f * (float) v );
			m->x[v] = spacing * (float) i + jx;
			m->y[v] = spacing * (float) j + jy;
			m->rim[v] = rim;
		}
	}
	/* Triangle 2 (j nx + i) + 0 is (v00, v10, v11), + 1 is (v00, v11, v01). */
	for ( int32_t j = 0; j < ny; ++j )
	{
		for ( int32_t i = 0; i < nx; ++i )
		{
			int32_t v00 = j * ( nx + 1 ) + i, v10 = v00 + 1, v01 = v00 + nx + 1, v11 = v01 + 1;
			int32_t corners[2][3] = { { v00, v10, v11 }, { v00, v11, v01 } };
			for ( int k = 0; k < 2; ++k )
			{
				int32_t t = nt + 2 * ( j * nx + i ) + k;
				m->x[t] = ( m->x[corners[k][0]] + m->x[corners[k][1]] + m->x[corners[k][2]] ) / 3.0f;
				m->y[t] = ( m->y[corners[k][0]] + m->y[corners[k][1]] + m->y[corners[k][2]] ) / 3.0f;
				m->z[t] = h;
			}
		}
	}
	for ( int32_t i = 0; i < m->n; ++i )
	{
		m->inv_m[i] = 1.0f;
	}
	for ( int32_t j = 0; j <= ny; ++j )
	{
		for ( int32_t i = 0; i <= nx; ++i )
		{
			int32_t v = j * ( nx + 1 ) + i;
			if ( i < nx )
			{
				add_spring( m, v, v + 1, 0 );
			}
			if ( j < ny )
			{
				add_spring( m, v, v + nx + 1, 0 );
			}
			if ( i < nx && j < ny )
			{
				add_spring( m, v, v + nx + 2, 0 );
			}
		}
	}
	for ( int32_t j = 0; j < ny; ++j )
	{
		for ( int32_t i = 0; i < nx; ++i )
		{
			int32_t t0 = nt + 2 * ( j * nx + i ), t1 = t0 + 1;
			add_spring( m, t0, t1, 1 ); /* across the cell's diagonal */
			if ( j > 0 )
			{
				add_spring( m, nt + 2 * ( ( j - 1 ) * nx + i ) + 1, t0, 1 ); /* across the bottom edge */
			}
			if ( i > 0 )
			{
				add_spring( m, nt + 2 * ( j * nx + i - 1 ), t1, 1 ); /* across the left edge */
			}
		}
	}
	for ( int32_t j = 0; j < ny; ++j )
	{
		for ( int32_t i = 0; i < nx; ++i )
		{
			int32_t v00 = j * ( nx + 1 ) + i, v10 = v00 + 1, v01 = v00 + nx + 1, v11 = v01 + 1;
			int32_t t0 = nt + 2 * ( j * nx + i );
			add_spring( m, v00, t0, 2 ), add_spring( m, v10, t0, 2 ), add_spring( m, v11, t0, 2 );
			add_spring( m, v00, t0 + 1, 2 ), add_spring( m, v11, t0 + 1, 2 ), add_spring( m, v01, t0 + 1, 2 );
		}
	}
	/* docs/DESIGN.md: springs = 12N − 6B − 12 for N triangle vertices, B of them on the outline. */
	cr_assert_eq( m->count, 12 * nt - 6 * 2 * ( nx + ny ) - 12 );
}

static float max_strain( const test_mesh* m, const float* rest )
{
	float worst = 0.0f;
	for ( int32_t s = 0; s < m->count; ++s )
	{
		float dx = m->x[m->b[s]] - m->x[m->a[s]], dy = m->y[m->b[s]] - m->y[m->a[s]];
		float dz = m->z[m->b[s]] - m->z[m->a[s]];
		float c = sqrtf( ( dx * dx + dy * dy ) + dz * dz ) - rest[s];
		worst = fmaxf( worst, fabsf( c ) / rest[s] );
	}
	return worst;
}

static sere_pbd* make_solver( const test_mesh* m, const float* rest )
{
	sere_pbd* pbd = NULL;
	cr_assert_eq( sere_pbd_create( m->a, m->b, m->count, m->n, &pbd ), SERE_OK );
	cr_assert_eq( sere_pbd_set_rest( pbd, rest ), SERE_OK );
	return pbd;
}

/* Projects a lone spring of rest length 1 from x = (0, 2) with inverse masses 1 and inv_m1;
 * returns the report, the positions in x. */
static sere_pbd_report spring_project( const sere_pbd_params* params, float inv_m1, float x[2] )
{
	int32_t a = 0, b = 1;
	float rest = 1.0f, inv_m[2] = { 1.0f, inv_m1 };
	float y[2] = { 0.0f, 0.0f }, z[2] = { 0.0f, 0.0f };
	x[0] = 0.0f, x[1] = 2.0f;
	sere_pbd* pbd;
	cr_assert_eq( sere_pbd_create( &a, &b, 1, 2, &pbd ), SERE_OK );
	cr_assert_eq( sere_pbd_set_rest( pbd, &rest ), SERE_OK );
	sere_pbd_report report;
	cr_assert_eq( sere_pbd_project( pbd, x, y, z, inv_m, params, &report ), SERE_OK );
	sere_pbd_destroy( pbd );
	return report;
}

Test( pbd, single_spring_reaches_rest_length )
{
	sere_pbd_params params = sere_pbd_params_default();
	float x[2];
	sere_pbd_report report = spring_project( &params, 3.0f, x );
	/* One projection solves a lone constraint; float rounding of the few operations: 1e-6. */
	cr_expect_float_eq( x[1] - x[0], 1.0f, 1e-6f );
	/* The correction splits by inverse mass: the end three times heavier moves a third as far. */
	cr_expect_float_eq( x[0], 0.25f, 1e-6f );
	cr_expect_float_eq( x[1], 1.25f, 1e-6f );
	/* Residuals are taken before each projection, so convergence shows in the second sweep. */
	cr_expect( !report.hit_cap && report.iterations == 2 && report.max_strain < 1e-6f, "%d sweeps, strain %g",
			   report.iterations, report.max_strain );
}

static float spring_after( const sere_pbd_params* params )
{
	float x[2];
	spring_project( params, 1.0f, x );
	return x[1] - x[0];
}

Test( pbd, stiffness_scales_the_correction )
{
	sere_pbd_params params = sere_pbd_params_default();
	params.stiffness = 0.5f;
	params.max_iterations = 1;
	/* One sweep with k = 0.5 removes half of C = 1 (float rounding: 1e-6). */
	cr_expect_float_eq( spring_after( &params ), 1.5f, 1e-6f );
	/* k' = 1 − (1 − k)^(1/4) applied in 4 sweeps leaves (1 − k') ^4 = 1 − k of C as well; k' is
	 * rounded to float, which moves the result by a few 1e-7. */
	params.max_iterations = 4;
	params.tolerance = 1e-9f;
	params.linear_stiffness = 1;
	cr_expect_float_eq( spring_after( &params ), 1.5f, 2e-6f );
	/* Without the correction the same 4 sweeps leave 0.5^4 of C. */
	params.linear_stiffness = 0;
	cr_expect_float_eq( spring_after( &params ), 1.0625f, 1e-6f );
}

Test( pbd, xpbd_compliance_leaves_the_one_step_equilibrium )
{
	/* One XPBD step on a lone spring ends where C + α̃ λ = 0 with Δλ = −C0/(w + α̃), i.e.
	 * C = C0 α̃/(w + α̃): here C0 = 1, w = 2, α̃ = α/dt² = 2, so the length is 1.5. */
	sere_pbd_params params = sere_pbd_params_default();
	params.dt = 0.01f;
	params.compliance = 2.0f * params.dt * params.dt;
	params.tolerance = 1e-6f;
	params.max_iterations = 10;
	cr_expect_float_eq( spring_after( &params ), 1.5f, 1e-6f );
	/* A tiny compliance is the rigid PBD spring again (α̃ = 1e-6: C = 5e-7). */
	params.compliance = 1e-6f * params.dt * params.dt;
	cr_expect_float_eq( spring_after( &params ), 1.0f, 2e-6f );
}

static void patch_converges( float scale, int jacobi )
{
	test_mesh m;
	cloth( &m, 20, 14, 0.1f );
	float* rest = malloc( sizeof( float ) * (size_t) m.count );
	memcpy( rest, m.rest, sizeof( float ) * (size_t) m.count );
	for ( int32_t i = 0; i < m.n; ++i )
	{
		m.x[i] *= scale;
		m.y[i] *= scale;
		/* A stretched patch starts slightly off the plane; a compressed one in it: the free
		 * patch only has to grow back, while out of the plane the colored order can fold it
		 * into a state it leaves very slowly (the natural order less so). */
		m.z[i] = scale > 1.0f ? 0.002f * sinf( 3.0f * m.x[i] ) * cosf( 2.0f * m.y[i] ) : 0.0f;
	}
	sere_pbd* pbd = make_solver( &m, rest );
	sere_pbd_params params = sere_pbd_params_default();
	params.max_iterations = 20000;
	sere_pbd_report report;
	sere_status status = jacobi ? sere_pbd_project_jacobi( pbd, m.x, m.y, m.z, m.inv_m, &params, &report )
								: sere_pbd_project( pbd, m.x, m.y, m.z, m.inv_m, &params, &report );
	cr_assert_eq( status, SERE_OK );
	cr_expect( !report.hit_cap, "scale %g: %d sweeps, strain %g", scale, report.iterations, report.max_strain );
	float after = max_strain( &m, rest );
	cr_expect_lt( after, params.tolerance, "scale %g: strain %g after %d sweeps", scale, after, report.iterations );
	/* The report describes the returned positions; the test measures them with the same
	 * float operations in the same order, so the two agree to the last bit. */
	cr_expect_eq( after, report.max_strain, "measured %.9g, reported %.9g", after, report.max_strain );
	free( rest );
	sere_pbd_destroy( pbd );
	mesh_free( &m );
}

Test( pbd, stretched_patch_converges )
{
	patch_converges( 1.2f, 0 );
}

Test( pbd, compressed_patch_converges )
{
	patch_converges( 0.9f, 0 );
}

Test( pbd, jacobi_converges_on_the_stretched_patch )
{
	patch_converges( 1.2f, 1 );
}

/* The double layer (double_layer) with its V springs (kind 1) shortened to 0.9 of their rest
 * length, and a solver on it. */
static sere_pbd* shrunk_solver( test_mesh* m, int32_t nx, int32_t ny, float spacing, float h, float jitter )
{
	double_layer( m, nx, ny, spacing, h, jitter );
	for ( int32_t s = 0; s < m->count; ++s )
	{
		m->rest[s] *= m->kind[s] == 1 ? 0.9f : 1.0f;
	}
	return make_solver( m, m->rest );
}

/* Runs a solver variant on a 60 × 40 double layer with shortened V springs at the current
 * thread count and returns the positions. */
static float* shrunk_layer_after( int variant )
{
	test_mesh m;
	sere_pbd* pbd = shrunk_solver( &m, 60, 40, 0.05f, 0.01f, 0.2f );
	/* More particles than one band holds: the sweeps run bands and cuts in parallel. */
	cr_assert_gt( sere_pbd_get_info( pbd ).bands, 1 );
	sere_pbd_params params = sere_pbd_params_default();
	params.max_iterations = 30;
	sere_pbd_report report;
	sere_status status;
	if ( variant == 0 )
	{
		status = sere_pbd_project( pbd, m.x, m.y, m.z, m.inv_m, &params, &report );
	}
	else if ( variant == 1 )
	{
		status = sere_pbd_project_jacobi( pbd, m.x, m.y, m.z, m.inv_m, &params, &report );
	}
	else
	{
		/* 2: XPBD; 3: XPBD with Chebyshev; 4: PBD with Chebyshev (extrapolated by thread
		 * shares with a barrier after, which must not depend on the threads either) */
		params.compliance = variant == 4 ? 0.0f : 1e-7f;
		params.chebyshev_rho = variant >= 3 ? 0.9f : 0.0f;
		params.chebyshev_delay = 3;
		status = sere_pbd_project( pbd, m.x, m.y, m.z, m.inv_m, &params, &report );
	}
	cr_assert_eq( status, SERE_OK );
	float* out = malloc( sizeof( float ) * 3 * (size_t) m.n );
	memcpy( out, m.x, sizeof( float ) * (size_t) m.n );
	memcpy( out + m.n, m.y, sizeof( float ) * (size_t) m.n );
	memcpy( out + 2 * m.n, m.z, sizeof( float ) * (size_t) m.n );
	sere_pbd_destroy( pbd );
	mesh_free( &m );
	return out;
}

/* One XPBD step of the shrunk double layer to a tight residual; returns the sweeps, positions
 * in xyz (3 n floats). */
static int32_t shrunk_step( float rho, float* xyz, int32_t* n )
{
	test_mesh m;
	sere_pbd* pbd = shrunk_solver( &m, 40, 30, 0.05f, 0.01f, 0.2f );
	sere_pbd_params params = sere_pbd_params_default();
	params.compliance = 1e-7f; /* α̃ = 0.025 */
	params.tolerance = 1e-5f;
	params.max_iterations = 5000;
	params.chebyshev_rho = rho;
	params.chebyshev_delay = 5;
	sere_pbd_report report;
	cr_assert_eq( sere_pbd_project( pbd, m.x, m.y, m.z, m.inv_m, &params, &report ), SERE_OK );
	cr_assert( !report.hit_cap, "rho %g: %d sweeps, residual %g", rho, report.iterations, report.max_strain );
	cr_assert_lt( report.max_strain, params.tolerance );
	*n = m.n;
	memcpy( xyz, m.x, sizeof( float ) * (size_t) m.n );
	memcpy( xyz + m.n, m.y, sizeof( float ) * (size_t) m.n );
	memcpy( xyz + 2 * m.n, m.z, sizeof( float ) * (size_t) m.n );
	sere_pbd_destroy( pbd );
	mesh_free( &m );
	return report.iterations;
}

Test( pbd, chebyshev_reaches_the_plain_step_in_fewer_sweeps )
{
	enum
	{
		capacity = 3 * ( 41 * 31 + 2 * 40 * 30 )
	};
	static float plain[capacity], fast[capacity];
	int32_t n = 0;
	int32_t sweeps_plain = shrunk_step( 0.0f, plain, &n );
	int32_t sweeps_fast = shrunk_step( 0.9f, fast, &n );
	cr_assert_leq( 3 * n, capacity );
	cr_expect_lt( sweeps_fast, sweeps_plain * 3 / 4, "Chebyshev %d sweeps, plain %d", sweeps_fast, sweeps_plain );
	float worst = 0.0f;
	for ( int32_t i = 0; i < n; ++i )
	{
		float dx = fast[i] - plain[i], dy = fast[n + i] - plain[n + i], dz = fast[2 * n + i] - plain[2 * n + i];
		worst = fmaxf( worst, sqrtf( dx * dx + dy * dy + dz * dz ) );
	}
	/* Both meet |C + α̃λ|/l < 1e-5. The sweeps solve the constraint equations and keep the
	 * inertia equation M (x − x̃) = ∇Cᵀλ only to first order along their path (Macklin et al.
	 * 2016 drop that residual), so two paths end a small distance apart that does not shrink
	 * with the tolerance: 1.1e-4 here at 1e-4, 1e-5 and 1e-6 (453/198, 632/277 and 810/359
	 * sweeps plain/Chebyshev). Bound: 1% of the spacing 0.05. */
	cr_expect_lt( worst, 5e-4f, "largest distance %g (spacing 0.05)", worst );
}

Test( pbd, chebyshev_arguments )
{
	test_mesh m;
	cloth( &m, 4, 4, 0.1f );
	sere_pbd* pbd = make_solver( &m, m.rest );
	sere_pbd_params params = sere_pbd_params_default();
	sere_pbd_report report;
	params.chebyshev_rho = 1.0f;
	cr_expect_eq( sere_pbd_project( pbd, m.x, m.y, m.z, m.inv_m, &params, &report ), SERE_ERR_ARGUMENT );
	params.chebyshev_rho = -0.1f;
	cr_expect_eq( sere_pbd_project( pbd, m.x, m.y, m.z, m.inv_m, &params, &report ), SERE_ERR_ARGUMENT );
	params.chebyshev_rho = 0.9f, params.chebyshev_delay = 1;
	cr_expect_eq( sere_pbd_project( pbd, m.x, m.y, m.z, m.inv_m, &params, &report ), SERE_ERR_ARGUMENT );
	params.chebyshev_delay = 2;
	cr_expect_eq( sere_pbd_project_jacobi( pbd, m.x, m.y, m.z, m.inv_m, &params, &report ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_pbd_project( pbd, m.x, m.y, m.z, m.inv_m, &params, &report ), SERE_OK );
	sere_pbd_destroy( pbd );
	mesh_free( &m );
}

Test( pbd, deterministic_across_threads )
{
	const char* names[5] = { "Gauss-Seidel", "Jacobi", "XPBD", "XPBD Chebyshev", "Gauss-Seidel Chebyshev" };
	for ( int variant = 0; variant < 5; ++variant )
	{
		omp_set_num_threads( 1 );
		float* one = shrunk_layer_after( variant );
		omp_set_num_threads( 2 );
		float* two = shrunk_layer_after( variant );
		/* Three threads do not divide the bands evenly: other work lists, other waits. */
		omp_set_num_threads( 3 );
		float* three = shrunk_layer_after( variant );
		size_t bytes = sizeof( float ) * 3 * ( 61 * 41 + 2 * 60 * 40 );
		cr_expect_eq( memcmp( one, two, bytes ), 0, "%s: 1 and 2 threads differ", names[variant] );
		cr_expect_eq( memcmp( one, three, bytes ), 0, "%s: 1 and 3 threads differ", names[variant] );
		free( one ), free( two ), free( three );
	}
}

/* One spring's projection (Jeong Eq. 13) with the kernel's operations in the kernel's order:
 * fmaf where the kernel fuses (one rounding), an explicit multiply and add where it does not (the
 * build contracts nothing), moving m's positions; returns the spring's |C/l| (|C + α̃λ|/l with
 * compliance) before the move. */
static float replay_spring( test_mesh* m, int32_t s, float rest, float k, float alpha, float* lambda )
{
	const int32_t a = m->a[s], b = m->b[s];
	float dx = m->x[b] - m->x[a], dy = m->y[b] - m->y[a], dz = m->z[b] - m->z[a];
	float len = sqrtf( fmaf( dz, dz, fmaf( dy, dy, dx * dx ) ) );
	float c = len - rest;
	float wsum = m->inv_m[a] + m->inv_m[b];
	float residual = c, f;
	if ( alpha > 0.0f )
	{
		residual = fmaf( alpha, *lambda, c );
		float denominator = wsum + alpha;
		*lambda = *lambda - ( denominator > 0.0f ? residual / denominator : 0.0f );
		f = denominator > 0.0f ? residual / ( denominator * len ) : 0.0f;
	}
	else
	{
		f = wsum > 0.0f ? ( k * c ) / ( wsum * len ) : 0.0f;
	}
	float fa = m->inv_m[a] * f, fb = m->inv_m[b] * f;
	m->x[a] = fmaf( fa, dx, m->x[a] ), m->y[a] = fmaf( fa, dy, m->y[a] ), m->z[a] = fmaf( fa, dz, m->z[a] );
	m->x[b] = fmaf( -fb, dx, m->x[b] ), m->y[b] = fmaf( -fb, dy, m->y[b] ), m->z[b] = fmaf( -fb, dz, m->z[b] );
	return fabsf( residual ) / rest;
}

Test( pbd, disjoint_springs_match_a_serial_replay_bit_for_bit )
{
	/* 2000 springs that share no particle: one color, long runs of SIMD blocks in two bands,
	 * and an order that cannot matter, so every SIMD path (the software-pipelined AVX one
	 * included) must give the bits of the one-spring formula applied spring by spring, sweep
	 * after sweep. Some ends pinned, one spring pinned at both ends. */
	const int32_t count = 2000;
	test_mesh m, replay;
	mesh_alloc( &m, 2 * count, count );
	mesh_alloc( &replay, 2 * count, count );
	for ( int32_t s = 0; s < count; ++s )
	{
		for ( int32_t e = 0; e < 2; ++e )
		{
			int32_t i = 2 * s + e;
			m.x[i] = 0.1f * (float) ( s % 50 ) + 0.07f * sinf( 1.7f * (float) i );
			m.y[i] = 0.1f * (float) ( s / 50 ) + 0.07f * cosf( 2.3f * (float) i );
			m.z[i] = 0.05f * sinf( 0.9f * (float) i );
			m.inv_m[i] = s % 7 == 3 && e == 0 ? 0.0f : 0.5f + (float) ( i % 5 );
		}
		m.inv_m[2 * s] = s == 11 ? 0.0f : m.inv_m[2 * s];
		m.inv_m[2 * s + 1] = s == 11 ? 0.0f : m.inv_m[2 * s + 1];
		m.a[s] = 2 * s, m.b[s] = 2 * s + 1;
		m.rest[s] = 0.05f + 0.002f * (float) ( s % 13 );
	}
	m.count = count;
	sere_pbd* pbd = make_solver( &m, m.rest );
	cr_assert_gt( sere_pbd_get_info( pbd ).bands, 1 );
	const size_t bytes = sizeof( float ) * (size_t) m.n;
	float* lambda = malloc( sizeof( float ) * (size_t) count );
	for ( int variant = 0; variant < 2; ++variant )
	{
		sere_pbd_params params = sere_pbd_params_default();
		params.stiffness = 0.8f;
		params.max_iterations = 3;
		params.tolerance = 1e-30f; /* never converged: exactly three sweeps */
		params.compliance = variant == 1 ? 1e-6f : 0.0f;
		const float alpha = variant == 1 ? params.compliance / ( params.dt * params.dt ) : 0.0f;
		memcpy( replay.x, m.x, bytes ), memcpy( replay.y, m.y, bytes ), memcpy( replay.z, m.z, bytes );
		memcpy( replay.inv_m, m.inv_m, bytes );
		memcpy( replay.a, m.a, sizeof( int32_t ) * (size_t) count );
		memcpy( replay.b, m.b, sizeof( int32_t ) * (size_t) count );
		memset( lambda, 0, sizeof( float ) * (size_t) count );
		float worst = 0.0f;
		for ( int32_t sweep = 0; sweep < params.max_iterations; ++sweep )
		{
			worst = 0.0f;
			for ( int32_t s = 0; s < count; ++s )
			{
				worst = fmaxf( worst, replay_spring( &replay, s, m.rest[s], params.stiffness, alpha, lambda + s ) );
			}
		}
		for ( int threads = 1; threads <= 2; ++threads )
		{
			omp_set_num_threads( threads );
			float* x = malloc( bytes );
			float* y = malloc( bytes );
			float* z = malloc( bytes );
			memcpy( x, m.x, bytes ), memcpy( y, m.y, bytes ), memcpy( z, m.z, bytes );
			sere_pbd_report report;
			cr_assert_eq( sere_pbd_project( pbd, x, y, z, m.inv_m, &params, &report ), SERE_OK );
			cr_expect_eq( report.iterations, params.max_iterations );
			cr_expect_eq( memcmp( x, replay.x, bytes ), 0, "variant %d, %d threads: x", variant, threads );
			cr_expect_eq( memcmp( y, replay.y, bytes ), 0, "variant %d, %d threads: y", variant, threads );
			cr_expect_eq( memcmp( z, replay.z, bytes ), 0, "variant %d, %d threads: z", variant, threads );
			cr_expect_eq( report.max_strain, worst, "variant %d: reported %.9g, replayed %.9g", variant,
						  report.max_strain, worst );
			free( x ), free( y ), free( z );
		}
	}
	free( lambda );
	sere_pbd_destroy( pbd );
	mesh_free( &m );
	mesh_free( &replay );
}

Test( pbd, colored_and_reference_reach_the_same_shape )
{
	/* An in-plane perturbation of a cloth pinned at its rim: the rest shape is the unique
	 * solution, so both solvers must reach it whatever their sweep order. */
	test_mesh m;
	cloth( &m, 20, 14, 0.1f );
	sere_ref_particle* ref = malloc( sizeof( sere_ref_particle ) * (size_t) m.n );
	sere_ref_spring* springs = malloc( sizeof( sere_ref_spring ) * (size_t) m.count );
	float* x0 = malloc( sizeof( float ) * (size_t) m.n );
	float* y0 = malloc( sizeof( float ) * (size_t) m.n );
	for ( int32_t i = 0; i < m.n; ++i )
	{
		x0[i] = m.x[i], y0[i] = m.y[i];
		m.inv_m[i] = m.rim[i] ? 0.0f : 1.0f;
		m.x[i] += m.rim[i] ? 0.0f : 0.03f * sinf( 7.0f * (float) i );
		m.y[i] += m.rim[i] ? 0.0f : 0.03f * cosf( 5.0f * (float) i );
		ref[i] = ( sere_ref_particle ){ m.x[i], m.y[i], m.z[i], m.inv_m[i] };
	}
	for ( int32_t s = 0; s < m.count; ++s )
	{
		springs[s] = ( sere_ref_spring ){ m.a[s], m.b[s], m.rest[s] };
	}
	sere_pbd* pbd = make_solver( &m, m.rest );
	sere_pbd_params params = sere_pbd_params_default();
	/* 1e-5: coordinates up to 2 have float ulps of 2.4e-7, which is a strain of 2.4e-6 on a
	 * spring of length 0.1, so much tighter tolerances sit in rounding noise. */
	params.tolerance = 1e-5f;
	params.max_iterations = 20000;
	sere_pbd_report report;
	cr_assert_eq( sere_pbd_project( pbd, m.x, m.y, m.z, m.inv_m, &params, &report ), SERE_OK );
	cr_assert( !report.hit_cap, "colored: %d sweeps, strain %g", report.iterations, report.max_strain );
	float ref_strain;
	int32_t sweeps = sere_pbd_ref_project( ref, springs, m.count, 1.0f, 1e-5f, 20000, &ref_strain );
	cr_assert_lt( ref_strain, 1e-5f, "reference: %d sweeps", sweeps );
	float worst = 0.0f, worst_rest = 0.0f;
	for ( int32_t i = 0; i < m.n; ++i )
	{
		worst = fmaxf( worst, fmaxf( fabsf( m.x[i] - ref[i].x ), fabsf( m.y[i] - ref[i].y ) ) );
		worst_rest = fmaxf( worst_rest, fmaxf( fabsf( m.x[i] - x0[i] ), fabsf( m.y[i] - y0[i] ) ) );
	}
	/* Strains below 1e-5 on springs of length 0.1 leave each spring within 1e-6 of its rest;
	 * errors add along the ~10 springs to the pinned rim: both shapes sit within 1e-4 (0.1% of
	 * a spacing) of the rest shape and of each other. */
	cr_expect_lt( worst_rest, 1e-4f, "colored vs rest shape: %g", worst_rest );
	cr_expect_lt( worst, 1e-4f, "colored vs reference: %g", worst );
	free( ref ), free( springs ), free( x0 ), free( y0 );
	sere_pbd_destroy( pbd );
	mesh_free( &m );
}

Test( pbd, shrinking_voronoi_layer_becomes_the_concave_side )
{
	/* Voronoi particles 0.03 above the triangle layer (+z). Shortening the V springs makes the
	 * upper layer the inner side of the bend (Fig. 2c, Fig. 14a): the rim rises toward the
	 * Voronoi side relative to the centre. */
	test_mesh m;
	sere_pbd* pbd = shrunk_solver( &m, 16, 16, 0.1f, 0.03f, 0.2f );
	sere_pbd_params params = sere_pbd_params_default();
	params.max_iterations = 3000;
	sere_pbd_report report;
	cr_assert_eq( sere_pbd_project( pbd, m.x, m.y, m.z, m.inv_m, &params, &report ), SERE_OK );
	double rim = 0.0, centre = 0.0;
	int32_t rim_count = 0, centre_count = 0;
	for ( int32_t i = 0; i < m.nt; ++i )
	{
		double r = hypot( m.x[i] - 0.8, m.y[i] - 0.8 );
		if ( m.rim[i] )
		{
			rim += m.z[i], rim_count += 1;
		}
		else if ( r < 0.25 )
		{
			centre += m.z[i], centre_count += 1;
		}
	}
	rim /= rim_count, centre /= centre_count;
	/* A 10% shorter upper layer at thickness 0.03 bends a 1.6-wide sheet by a sagitta of
	 * order 0.1; 0.05 leaves room for the strain the cap leaves. */
	cr_expect_gt( rim - centre, 0.05, "rim %g centre %g after %d sweeps", rim, centre, report.iterations );
	sere_pbd_destroy( pbd );
	mesh_free( &m );
}

Test( pbd, touch_leaves_positions_unchanged )
{
	test_mesh m;
	double_layer( &m, 60, 40, 0.05f, 0.01f, 0.2f );
	size_t bytes = sizeof( float ) * (size_t) m.n;
	float* before = malloc( 3 * bytes );
	memcpy( before, m.x, bytes ), memcpy( before + m.n, m.y, bytes ), memcpy( before + 2 * m.n, m.z, bytes );
	sere_pbd* pbd;
	cr_assert_eq( sere_pbd_create( m.a, m.b, m.count, m.n, &pbd ), SERE_OK );
	cr_assert_eq( sere_pbd_touch( pbd, m.x, m.y, m.z, m.inv_m ), SERE_OK );
	cr_expect_eq( memcmp( before, m.x, bytes ), 0 );
	cr_expect_eq( memcmp( before + m.n, m.y, bytes ), 0 );
	cr_expect_eq( memcmp( before + 2 * m.n, m.z, bytes ), 0 );
	/* The multi-sweep floor, at both thread counts. */
	for ( int threads = 1; threads <= 2; ++threads )
	{
		omp_set_num_threads( threads );
		cr_assert_eq( sere_pbd_touch_sweeps( pbd, m.x, m.y, m.z, m.inv_m, 7 ), SERE_OK );
		cr_expect_eq( memcmp( before, m.x, bytes ), 0, "%d threads", threads );
		cr_expect_eq( memcmp( before + m.n, m.y, bytes ), 0, "%d threads", threads );
		cr_expect_eq( memcmp( before + 2 * m.n, m.z, bytes ), 0, "%d threads", threads );
		/* and XPBD's, which also reads the weights and multipliers */
		cr_assert_eq( sere_pbd_touch_sweeps_xpbd( pbd, m.x, m.y, m.z, m.inv_m, 7 ), SERE_OK );
		cr_expect_eq( memcmp( before, m.x, bytes ), 0, "XPBD, %d threads", threads );
		cr_expect_eq( memcmp( before + m.n, m.y, bytes ), 0, "XPBD, %d threads", threads );
		cr_expect_eq( memcmp( before + 2 * m.n, m.z, bytes ), 0, "XPBD, %d threads", threads );
	}
	cr_expect_eq( sere_pbd_touch_sweeps( pbd, m.x, m.y, m.z, m.inv_m, 0 ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_pbd_touch_sweeps_xpbd( pbd, m.x, m.y, m.z, m.inv_m, 0 ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_pbd_touch_sweeps_xpbd( NULL, m.x, m.y, m.z, m.inv_m, 1 ), SERE_ERR_ARGUMENT );
	sere_pbd_info info = sere_pbd_get_info( pbd );
	cr_expect_eq( info.lanes % 16, 0 );
	cr_expect_geq( info.lanes, m.count );
	cr_expect_leq( info.interface_constraints, m.count / 4, "bands should cut few constraints: %d of %d",
				   info.interface_constraints, m.count );
	free( before );
	sere_pbd_destroy( pbd );
	mesh_free( &m );
}

Test( pbd, predict_and_finish )
{
	float x[2] = { 1.0f, 2.0f }, y[2] = { 0.0f, 0.0f }, z[2] = { 0.0f, 0.0f };
	float vx[2] = { 0.5f, 0.5f }, vy[2] = { 0.0f, 0.0f }, vz[2] = { 0.0f, 0.0f };
	float px[2], py[2], pz[2], inv_m[2] = { 1.0f, 0.0f };
	const float gravity[3] = { 0.0f, 0.0f, -9.8f }, dt = 0.01f;
	sere_pbd_predict( 2, x, y, z, vx, vy, vz, px, py, pz, inv_m, gravity, dt, 0 );
	/* Same float operations as the kernel (v += g dt, p = x + v dt), so exact equality. */
	float vz0 = 0.0f + -9.8f * dt;
	cr_expect_eq( vz[0], vz0 );
	cr_expect_eq( pz[0], 0.0f + vz0 * dt );
	cr_expect_eq( px[0], 1.0f + 0.5f * dt );
	/* A pinned particle has no velocity and stays. */
	cr_expect( vx[1] == 0.0f && vz[1] == 0.0f && px[1] == 2.0f && pz[1] == 0.0f );
	px[0] = 1.5f;
	sere_pbd_finish( 2, x, y, z, vx, vy, vz, px, py, pz, dt, 0 );
	cr_expect_eq( x[0], 1.5f );
	cr_expect_eq( vx[0], ( 1.5f - 1.0f ) * ( 1.0f / dt ) );
	cr_expect_eq( z[0], 0.0f + vz0 * dt );
}

Test( pbd, bad_input_gives_errors_and_leaves_positions )
{
	int32_t a[2] = { 0, 1 }, b[2] = { 1, 2 };
	float rest[2] = { 1.0f, 1.0f }, inv_m[3] = { 1.0f, 1.0f, 1.0f };
	float x[3] = { 0.0f, 1.5f, 2.0f }, y[3] = { 0 }, z[3] = { 0 };
	sere_pbd* pbd;
	sere_pbd_params params = sere_pbd_params_default();
	sere_pbd_report report;
	cr_assert_eq( sere_pbd_create( a, b, 2, 3, &pbd ), SERE_OK );
	/* No rest lengths yet, then invalid ones: the projections refuse. */
	cr_expect_eq( sere_pbd_project( pbd, x, y, z, inv_m, &params, &report ), SERE_ERR_GEOMETRY );
	float zero[2] = { 1.0f, 0.0f }, nan_rest[2] = { NAN, 1.0f };
	cr_expect_eq( sere_pbd_set_rest( pbd, zero ), SERE_ERR_GEOMETRY );
	cr_expect_eq( sere_pbd_project( pbd, x, y, z, inv_m, &params, &report ), SERE_ERR_GEOMETRY );
	cr_expect_eq( sere_pbd_set_rest( pbd, nan_rest ), SERE_ERR_GEOMETRY );
	cr_assert_eq( sere_pbd_set_rest( pbd, rest ), SERE_OK );

	const float x_in[3] = { 0.0f, 1.5f, 2.0f };
	x[1] = NAN;
	cr_expect_eq( sere_pbd_project( pbd, x, y, z, inv_m, &params, &report ), SERE_ERR_NONFINITE );
	cr_expect( isnan( x[1] ) && x[0] == 0.0f && x[2] == 2.0f, "nothing touched" );
	x[1] = INFINITY;
	cr_expect_eq( sere_pbd_project_jacobi( pbd, x, y, z, inv_m, &params, &report ), SERE_ERR_NONFINITE );
	x[1] = 1.5f;
	inv_m[2] = INFINITY;
	cr_expect_eq( sere_pbd_project( pbd, x, y, z, inv_m, &params, &report ), SERE_ERR_NONFINITE );
	inv_m[2] = -1.0f;
	cr_expect_eq( sere_pbd_project( pbd, x, y, z, inv_m, &params, &report ), SERE_ERR_ARGUMENT );
	inv_m[2] = 1.0f;
	cr_expect_eq( memcmp( x, x_in, sizeof( x ) ), 0, "nothing touched" );

	/* Particles 0 and 1 coincide: a zero-length spring is found in the sweep; the error
	 * comes back and the caller's positions are as they were (no NaN). */
	x[1] = 0.0f;
	cr_expect_eq( sere_pbd_project( pbd, x, y, z, inv_m, &params, &report ), SERE_ERR_GEOMETRY );
	cr_expect( x[0] == 0.0f && x[1] == 0.0f && x[2] == 2.0f, "nothing touched" );
	cr_expect_eq( sere_pbd_project_jacobi( pbd, x, y, z, inv_m, &params, &report ), SERE_ERR_GEOMETRY );
	/* Finite positions whose squared distance overflows float. */
	x[1] = 3e38f;
	cr_expect_eq( sere_pbd_project( pbd, x, y, z, inv_m, &params, &report ), SERE_ERR_NONFINITE );
	cr_expect( x[0] == 0.0f && x[1] == 3e38f && x[2] == 2.0f, "nothing touched" );
	x[1] = 1.5f;

	sere_pbd_params bad = params;
	bad.stiffness = 1.5f;
	cr_expect_eq( sere_pbd_project( pbd, x, y, z, inv_m, &bad, &report ), SERE_ERR_ARGUMENT );
	bad = params, bad.tolerance = 0.0f;
	cr_expect_eq( sere_pbd_project( pbd, x, y, z, inv_m, &bad, &report ), SERE_ERR_ARGUMENT );
	bad = params, bad.max_iterations = 0;
	cr_expect_eq( sere_pbd_project( pbd, x, y, z, inv_m, &bad, &report ), SERE_ERR_ARGUMENT );
	bad = params, bad.compliance = -1.0f;
	cr_expect_eq( sere_pbd_project( pbd, x, y, z, inv_m, &bad, &report ), SERE_ERR_ARGUMENT );
	bad = params, bad.compliance = 1.0f, bad.dt = 0.0f;
	cr_expect_eq( sere_pbd_project( pbd, x, y, z, inv_m, &bad, &report ), SERE_ERR_ARGUMENT );
	bad = params, bad.relaxation = 2.0f;
	cr_expect_eq( sere_pbd_project_jacobi( pbd, x, y, z, inv_m, &bad, &report ), SERE_ERR_ARGUMENT );
	cr_expect_eq( memcmp( x, x_in, sizeof( x ) ), 0, "nothing touched" );
	sere_pbd_destroy( pbd );

	sere_pbd* none = NULL;
	int32_t self[1] = { 1 }, out_of_range[1] = { 3 };
	cr_expect_eq( sere_pbd_create( self, self, 1, 3, &none ), SERE_ERR_ARGUMENT );
	cr_expect_eq( sere_pbd_create( a, out_of_range, 1, 3, &none ), SERE_ERR_ARGUMENT );
	cr_expect_null( none );
}

Test( pbd, bad_values_are_found_in_every_band_at_both_thread_counts )
{
	/* Each thread checks the records of its own bands: a bad value in the first, a middle or
	 * the last particle is found wherever it lands, and nothing is written back. */
	test_mesh m;
	double_layer( &m, 60, 40, 0.05f, 0.01f, 0.2f );
	sere_pbd* pbd = make_solver( &m, m.rest );
	cr_assert_gt( sere_pbd_get_info( pbd ).bands, 1 );
	size_t bytes = sizeof( float ) * (size_t) m.n;
	float* before = malloc( bytes );
	memcpy( before, m.x, bytes );
	sere_pbd_params params = sere_pbd_params_default();
	sere_pbd_report report;
	const int32_t where[3] = { 0, m.n / 2, m.n - 1 };
	for ( int threads = 1; threads <= 2; ++threads )
	{
		omp_set_num_threads( threads );
		for ( int k = 0; k < 3; ++k )
		{
			int32_t i = where[k];
			float saved = m.y[i];
			m.y[i] = NAN;
			cr_expect_eq( sere_pbd_project( pbd, m.x, m.y, m.z, m.inv_m, &params, &report ), SERE_ERR_NONFINITE,
						  "NaN at %d, %d threads", i, threads );
			m.y[i] = saved;
			saved = m.inv_m[i];
			m.inv_m[i] = -1.0f;
			cr_expect_eq( sere_pbd_project( pbd, m.x, m.y, m.z, m.inv_m, &params, &report ), SERE_ERR_ARGUMENT,
						  "negative mass at %d, %d threads", i, threads );
			m.inv_m[i] = saved;
			cr_expect_eq( memcmp( before, m.x, bytes ), 0, "nothing touched" );
		}
	}
	free( before );
	sere_pbd_destroy( pbd );
	mesh_free( &m );
}

/* The sign of the Gaussian curvature of the least-squares quadric z = a x² + b xy + c y² + d x
 * + e y + f through the triangle layer (x, y about the sheet's centre): 4ac − b², which has the
 * sign of K at the centre. */
static double quadric_curvature( const test_mesh* m, float cx, float cy )
{
	double a[6][7] = { { 0 } };
	for ( int32_t i = 0; i < m->nt; ++i )
	{
		double x = m->x[i] - cx, y = m->y[i] - cy;
		double row[6] = { x * x, x * y, y * y, x, y, 1.0 };
		for ( int r = 0; r < 6; ++r )
		{
			for ( int c = 0; c < 6; ++c )
			{
				a[r][c] += row[r] * row[c];
			}
			a[r][6] += row[r] * m->z[i];
		}
	}
	/* the normal equations are SPD: elimination without pivoting */
	for ( int k = 0; k < 6; ++k )
	{
		for ( int r = k + 1; r < 6; ++r )
		{
			double f = a[r][k] / a[k][k];
			for ( int c = k; c < 7; ++c )
			{
				a[r][c] -= f * a[k][c];
			}
		}
	}
	double q[6];
	for ( int k = 5; k >= 0; --k )
	{
		double sum = a[k][6];
		for ( int c = k + 1; c < 6; ++c )
		{
			sum -= a[k][c] * q[c];
		}
		q[k] = sum / a[k][k];
	}
	return 4.0 * q[0] * q[2] - q[1] * q[1];
}

typedef enum shrink_profile
{
	SHRINK_UNIFORM,
	SHRINK_CENTRE_MORE,
	SHRINK_RIM_MORE,
} shrink_profile;

/* Fig. 14 (b, c): a thin double layer (1.2 wide, 0.005 thick, the paper's 1:0.002–0.001 order)
 * whose two layers shrink alike, by a loss that depends on the distance from the centre, ramped
 * in over 200 frames as drying would and then left to settle for 200 more, without gravity.
 * Reports the triangle layer's out-of-plane extent and the curvature sign of its quadric. */
static void buckle( shrink_profile profile, double* extent, double* curvature )
{
	const int32_t nx = 24;
	const float spacing = 0.05f, half = 0.5f * spacing * (float) nx;
	test_mesh m;
	double_layer( &m, nx, nx, spacing, 0.005f, 0.2f );
	float* loss = malloc( sizeof( float ) * (size_t) m.count );
	float* rest = malloc( sizeof( float ) * (size_t) m.count );
	for ( int32_t s = 0; s < m.count; ++s )
	{
		float mx = 0.5f * ( m.x[m.a[s]] + m.x[m.b[s]] ) - half, my = 0.5f * ( m.y[m.a[s]] + m.y[m.b[s]] ) - half;
		float r = fminf( sqrtf( mx * mx + my * my ) / half, 1.0f );
		loss[s] = profile == SHRINK_UNIFORM ? 0.05f : profile == SHRINK_CENTRE_MORE ? 0.1f * ( 1.0f - r ) : 0.1f * r;
	}
	/* a perturbation far below the thickness, so that the flat state is not an exact symmetry */
	for ( int32_t i = 0; i < m.n; ++i )
	{
		m.z[i] += 1e-4f * sinf( 3.1f * m.x[i] + 1.7f * m.y[i] * m.y[i] );
	}
	sere_pbd* pbd = make_solver( &m, m.rest );
	sere_pbd_params params = sere_pbd_params_default();
	params.max_iterations = 100;
	size_t bytes = sizeof( float ) * (size_t) m.n;
	float *vx = calloc( 1, bytes ), *vy = calloc( 1, bytes ), *vz = calloc( 1, bytes );
	float *px = malloc( bytes ), *py = malloc( bytes ), *pz = malloc( bytes );
	const float gravity[3] = { 0.0f, 0.0f, 0.0f };
	for ( int frame = 0; frame < 400; ++frame )
	{
		float ramp = fminf( 1.0f, (float) frame / 200.0f );
		for ( int32_t s = 0; s < m.count; ++s )
		{
			rest[s] = m.rest[s] * ( 1.0f - ramp * loss[s] );
		}
		cr_assert_eq( sere_pbd_set_rest( pbd, rest ), SERE_OK );
		sere_pbd_predict( m.n, m.x, m.y, m.z, vx, vy, vz, px, py, pz, m.inv_m, gravity, params.dt, 0 );
		sere_pbd_report report;
		cr_assert_eq( sere_pbd_project( pbd, px, py, pz, m.inv_m, &params, &report ), SERE_OK );
		sere_pbd_finish( m.n, m.x, m.y, m.z, vx, vy, vz, px, py, pz, params.dt, 0 );
		for ( int32_t i = 0; i < m.n; ++i )
		{
			vx[i] *= 0.98f, vy[i] *= 0.98f, vz[i] *= 0.98f; /* air damping, so the sheet settles */
		}
	}
	double lo = INFINITY, hi = -INFINITY;
	for ( int32_t i = 0; i < m.nt; ++i )
	{
		lo = fmin( lo, m.z[i] ), hi = fmax( hi, m.z[i] );
	}
	*extent = hi - lo;
	*curvature = quadric_curvature( &m, half, half );
	free( vx ), free( vy ), free( vz ), free( px ), free( py ), free( pz ), free( loss ), free( rest );
	sere_pbd_destroy( pbd );
	mesh_free( &m );
}

Test( pbd, fig14_uneven_shrinkage_buckles )
{
	double extent, curvature;
	/* Shrinking the same everywhere leaves a stress-free, smaller flat sheet: its extent stays
	 * at the order of the 1e-4 perturbation and the strain the sweeps leave (measured 1.2e-3;
	 * bound 1% of the width). */
	buckle( SHRINK_UNIFORM, &extent, &curvature );
	cr_expect_lt( extent, 0.012, "uniform shrinkage buckled: extent %g", extent );
	/* (b) the centre shrinks more: the rim is too long for it and the sheet takes negative
	 * Gaussian curvature, a saddle (measured extent 0.28, 4ac − b² = −0.17). */
	buckle( SHRINK_CENTRE_MORE, &extent, &curvature );
	cr_expect_gt( extent, 0.1, "centre shrinking more: extent %g", extent );
	cr_expect_lt( curvature, -0.02, "centre shrinking more: 4ac - b^2 = %g, not a saddle", curvature );
	/* (c) the rim shrinks more: the centre has too much area and bulges, positive curvature
	 * (measured extent 0.21, 4ac − b² = +0.24). */
	buckle( SHRINK_RIM_MORE, &extent, &curvature );
	cr_expect_gt( extent, 0.1, "rim shrinking more: extent %g", extent );
	cr_expect_gt( curvature, 0.02, "rim shrinking more: 4ac - b^2 = %g, not a dome", curvature );
}
