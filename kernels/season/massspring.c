/* _GNU_SOURCE: sched_getaffinity for core/internal/team.h. */
#define _GNU_SOURCE

#include "season/internal/massspring_shared.h"

#include "core/array.h"

#include <math.h>
#include <stdbool.h>
#include <stdlib.h>

#include "core/internal/simd.h"
#include "core/internal/team.h"

sere_massspring_params sere_massspring_params_default( void )
{
	sere_massspring_params p;
	p.dt = 1e-3f;
	p.gravity[0] = 0.0f;
	p.gravity[1] = 0.0f;
	p.gravity[2] = -1.0f;
	p.stiffness = 40.0f;
	p.bend_stiffness = 4.0f;
	p.damping = 0.02f;
	p.drag = 0.01f;
	p.shrink = 0.0f;
	p.curl = 0.0f;
	p.strain_limit = 0.1f;
	p.strain_tolerance = 1e-3f;
	p.max_sweeps = 500;
	return p;
}

sere_status sere_massspring_mass_from_gray( const float* gray, int32_t n, float m_min, float m_max, float* mass )
{
	if ( n < 0 || ( n > 0 && ( gray == NULL || mass == NULL ) ) || !isfinite( m_min ) || !isfinite( m_max ) ||
		 !( m_min > 0.0f ) || !( m_min <= m_max ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	for ( int32_t i = 0; i < n; ++i )
	{
		if ( isnan( gray[i] ) )
		{
			return SERE_ERR_NONFINITE;
		}
	}
	const double scale = 1.0 / log( 256.0 );
	for ( int32_t i = 0; i < n; ++i )
	{
		double g = gray[i] < 0.0f ? 0.0 : ( gray[i] > 1.0f ? 1.0 : (double) gray[i] );
		double t = log1p( 255.0 * g ) * scale; /* Tang Eq. 3 */
		mass[i] = (float) ( m_min + ( (double) m_max - m_min ) * t );
	}
	return SERE_OK;
}

sere_status sere_massspring_set_threads( sere_massspring* ms, int32_t threads )
{
	return ms == NULL ? SERE_ERR_ARGUMENT : sere_threads_store( &ms->threads, threads );
}

void sere_massspring_destroy( sere_massspring* ms )
{
	if ( ms == NULL )
	{
		return;
	}
	sere_free( ms->a );
	sere_free( ms->b );
	sere_free( ms->rest0 );
	sere_free( ms->run_offsets );
	sere_free( ms->incidence_offsets );
	sere_free( ms->incidence );
	sere_free( ms->incidence_sign );
	sere_free( ms->fx );
	sere_free( ms->fy );
	sere_free( ms->fz );
	sere_free( ms->xrec );
	sere_free( ms->vrec );
	free( ms );
}

static int params_valid( const sere_massspring_params* p )
{
	return isfinite( p->dt ) && p->dt > 0.0f && isfinite( p->gravity[0] ) && isfinite( p->gravity[1] ) &&
		   isfinite( p->gravity[2] ) && isfinite( p->stiffness ) && p->stiffness >= 0.0f &&
		   isfinite( p->bend_stiffness ) && p->bend_stiffness >= 0.0f && isfinite( p->damping ) && p->damping >= 0.0f &&
		   p->drag >= 0.0f && p->drag < 1.0f && p->shrink >= 0.0f && p->shrink < 1.0f && p->curl >= 0.0f &&
		   p->curl < 1.0f && p->strain_limit > 0.0f && p->strain_limit < 1.0f && p->strain_tolerance > 0.0f &&
		   p->strain_tolerance < p->strain_limit && p->max_sweeps >= 1;
}

/* The constants of one kind of spring in one step. */
typedef struct spring_law
{
	float keep; /* L = keep · L⁰ */
	float k;	/* stiffness */
	float c;	/* damping */
} spring_law;

/* The spring indices of a chunk of SERE_LANES from [s, s + left); lanes past the end repeat
 * lane 0, whose particles this chunk owns, so their loads never read a record another thread
 * writes. */
static inline int32_t chunk_ends( const int32_t* sa, const int32_t* sb, int32_t s, int32_t left, int32_t* ia,
								  int32_t* ib )
{
	const int32_t lanes = left < SERE_LANES ? left : SERE_LANES;
	for ( int32_t j = 0; j < SERE_LANES; ++j )
	{
		ia[j] = sa[s + ( j < lanes ? j : 0 )];
		ib[j] = sb[s + ( j < lanes ? j : 0 )];
	}
	return lanes;
}

/* Packs the particles into records (x, y, z, 1/m) and (vx, vy, vz, 0). */
static void pack( sere_massspring* ms, const sere_massspring_particles* p )
{
	float* restrict xr = ms->xrec;
	float* restrict vr = ms->vrec;
#pragma omp for schedule( static )
	for ( int32_t i = 0; i < p->count; ++i )
	{
		xr[4 * i] = p->x[i];
		xr[4 * i + 1] = p->y[i];
		xr[4 * i + 2] = p->z[i];
		xr[4 * i + 3] = p->inv_m[i];
		vr[4 * i] = p->vx[i];
		vr[4 * i + 1] = p->vy[i];
		vr[4 * i + 2] = p->vz[i];
		vr[4 * i + 3] = 0.0f;
	}
}

/* a + b + c + d: what the floor's passes (touch) do with the records they load, in place of the
 * step's arithmetic, so that no load can be left out. */
static inline sere_vf sum4( sere_vf a, sere_vf b, sere_vf c, sere_vf d )
{
	return sere_vf_add( sere_vf_add( a, b ), sere_vf_add( c, d ) );
}

/* The per-spring forces of springs [first, first + count) (see the header for the law); with
 * touch, the same loads and stores with sums of the loaded values for forces (the floor). */
static void spring_forces( sere_massspring* ms, int32_t first, int32_t count, spring_law law, bool touch )
{
	const int32_t* restrict sa = ms->a;
	const int32_t* restrict sb = ms->b;
	const float* restrict rest0 = ms->rest0;
	const float* restrict xr = ms->xrec;
	const float* restrict vr = ms->vrec;
	float* restrict fx = ms->fx;
	float* restrict fy = ms->fy;
	float* restrict fz = ms->fz;
	const int32_t chunks = ( count + SERE_LANES - 1 ) / SERE_LANES;
	const sere_vf keep = sere_vf_splat( law.keep ), k = sere_vf_splat( law.k ), c = sere_vf_splat( law.c );
	const sere_vf one = sere_vf_splat( 1.0f ), zero = sere_vf_splat( 0.0f );
#pragma omp for schedule( static )
	for ( int32_t chunk = 0; chunk < chunks; ++chunk )
	{
		const int32_t s = first + SERE_LANES * chunk;
		int32_t ia[SERE_LANES], ib[SERE_LANES];
		const int32_t lanes = chunk_ends( sa, sb, s, count - SERE_LANES * chunk, ia, ib );
		sere_vf ax, ay, az, aw, bx, by, bz, bw, avx, avy, avz, bvx, bvy, bvz, unused;
		sere_vf_load_records( xr, ia, &ax, &ay, &az, &aw );
		sere_vf_load_records( xr, ib, &bx, &by, &bz, &bw );
		sere_vf_load_records( vr, ia, &avx, &avy, &avz, &unused );
		sere_vf_load_records( vr, ib, &bvx, &bvy, &bvz, &unused );
		if ( touch )
		{
			sere_vf r = sere_vf_add( sere_vf_load_first( rest0 + s, lanes, 1.0f ), sere_vf_add( aw, bw ) );
			sere_vf_store_first( fx + s, lanes, sere_vf_add( sum4( ax, bx, avx, bvx ), r ) );
			sere_vf_store_first( fy + s, lanes, sum4( ay, by, avy, bvy ) );
			sere_vf_store_first( fz + s, lanes, sum4( az, bz, avz, bvz ) );
			continue;
		}
		sere_vf dx = sere_vf_sub( bx, ax ), dy = sere_vf_sub( by, ay ), dz = sere_vf_sub( bz, az );
		sere_vf len = sere_vf_norm3( dx, dy, dz );
		sere_vf inv = sere_vf_keep( sere_vf_gt( len, zero ), sere_vf_div( one, len ) );
		sere_vf nx = sere_vf_mul( dx, inv ), ny = sere_vf_mul( dy, inv ), nz = sere_vf_mul( dz, inv );
		sere_vf rest = sere_vf_mul( sere_vf_load_first( rest0 + s, lanes, 1.0f ), keep );
		sere_vf strain = sere_vf_div( sere_vf_sub( len, rest ), rest );
		sere_vf rvx = sere_vf_sub( bvx, avx ), rvy = sere_vf_sub( bvy, avy ), rvz = sere_vf_sub( bvz, avz );
		sere_vf along =
			sere_vf_add( sere_vf_add( sere_vf_mul( rvx, nx ), sere_vf_mul( rvy, ny ) ), sere_vf_mul( rvz, nz ) );
		sere_vf f = sere_vf_add( sere_vf_mul( k, strain ), sere_vf_mul( c, along ) );
		sere_vf_store_first( fx + s, lanes, sere_vf_mul( f, nx ) );
		sere_vf_store_first( fy + s, lanes, sere_vf_mul( f, ny ) );
		sere_vf_store_first( fz + s, lanes, sere_vf_mul( f, nz ) );
	}
}

/* Tang Eq. 1: every particle gathers its springs' forces in a fixed order, then a = g + F/m,
 * v ← (1 − drag)(v + a Δt), in the velocity records. */
static void integrate_velocities( sere_massspring* ms, int32_t count, const sere_massspring_params* params )
{
	const int32_t* restrict offsets = ms->incidence_offsets;
	const int32_t* restrict incidence = ms->incidence;
	const float* restrict sign = ms->incidence_sign;
	const float* restrict fx = ms->fx;
	const float* restrict fy = ms->fy;
	const float* restrict fz = ms->fz;
	const float* restrict xr = ms->xrec;
	float* restrict vr = ms->vrec;
	const float dt = params->dt, keep = 1.0f - params->drag;
	const float gx = params->gravity[0], gy = params->gravity[1], gz = params->gravity[2];
#pragma omp for schedule( static )
	for ( int32_t i = 0; i < count; ++i )
	{
		float sx = 0.0f, sy = 0.0f, sz = 0.0f;
		for ( int32_t e = offsets[i]; e < offsets[i + 1]; ++e )
		{
			const int32_t s = incidence[e];
			sx += sign[e] * fx[s];
			sy += sign[e] * fy[s];
			sz += sign[e] * fz[s];
		}
		const float w = xr[4 * i + 3];
		float* v = vr + 4 * i;
		if ( w > 0.0f )
		{
			v[0] = ( v[0] + dt * ( gx + w * sx ) ) * keep;
			v[1] = ( v[1] + dt * ( gy + w * sy ) ) * keep;
			v[2] = ( v[2] + dt * ( gz + w * sz ) ) * keep;
		}
		else
		{
			v[0] = 0.0f;
			v[1] = 0.0f;
			v[2] = 0.0f;
		}
	}
}

/* Tang Eq. 2 on one run of structural springs [first, first + count), by the calling thread: no two
 * of them share a particle, so they are limited at the same time (SERE_LANES to a step of the lane layer). Each spring
 * off [lo_factor L, hi_factor L] gets its relative velocity changed along p = x_ab + v_ab Δt so that |p| lands on the
 * nearer bound. Raises *worst_io to the largest distance off the band (relative to L) this thread found before
 * correcting and adds the number of its springs that were off to *off_band. With touch, the same loads summed
 * into *worst_io and nothing stored (the floor). */
static void limit_run( sere_massspring* ms, int32_t first, int32_t count, float keep, float lo_factor, float hi_factor,
					   float dt, bool touch, float* worst_io, int32_t* off_band )
{
	const int32_t* restrict sa = ms->a;
	const int32_t* restrict sb = ms->b;
	const float* restrict rest0 = ms->rest0;
	const float* restrict xr = ms->xrec;
	float* restrict vr = ms->vrec;
	float worst = *worst_io;
	int32_t n = 0;
	const int32_t chunks = ( count + SERE_LANES - 1 ) / SERE_LANES;
	const sere_vf vkeep = sere_vf_splat( keep ), vlo = sere_vf_splat( lo_factor ), vhi = sere_vf_splat( hi_factor );
	const sere_vf vdt = sere_vf_splat( dt ), zero = sere_vf_splat( 0.0f );
	sere_vf touched = zero;
	for ( int32_t chunk = 0; chunk < chunks; ++chunk )
	{
		const int32_t s = first + SERE_LANES * chunk;
		int32_t ia[SERE_LANES], ib[SERE_LANES];
		const int32_t lanes = chunk_ends( sa, sb, s, count - SERE_LANES * chunk, ia, ib );
		sere_vf ax, ay, az, wa, bx, by, bz, wb, avx, avy, avz, avw, bvx, bvy, bvz, bvw;
		sere_vf_load_records( xr, ia, &ax, &ay, &az, &wa );
		sere_vf_load_records( xr, ib, &bx, &by, &bz, &wb );
		sere_vf_load_records( vr, ia, &avx, &avy, &avz, &avw );
		sere_vf_load_records( vr, ib, &bvx, &bvy, &bvz, &bvw );
		if ( touch )
		{
			sere_vf r = sere_vf_add( sere_vf_load_first( rest0 + s, lanes, 1.0f ), sum4( wa, wb, avw, bvw ) );
			touched = sere_vf_add( touched, sere_vf_add( sum4( ax, bx, avx, bvx ), r ) );
			touched = sere_vf_add( touched, sere_vf_add( sum4( ay, by, avy, bvy ), sum4( az, bz, avz, bvz ) ) );
			continue;
		}
		sere_vf px = sere_vf_add( sere_vf_sub( bx, ax ), sere_vf_mul( vdt, sere_vf_sub( bvx, avx ) ) );
		sere_vf py = sere_vf_add( sere_vf_sub( by, ay ), sere_vf_mul( vdt, sere_vf_sub( bvy, avy ) ) );
		sere_vf pz = sere_vf_add( sere_vf_sub( bz, az ), sere_vf_mul( vdt, sere_vf_sub( bvz, avz ) ) );
		sere_vf len = sere_vf_norm3( px, py, pz );
		sere_vf rest = sere_vf_mul( sere_vf_load_first( rest0 + s, lanes, 1.0f ), vkeep );
		sere_vf target = sere_vf_min( sere_vf_max( len, sere_vf_mul( rest, vlo ) ), sere_vf_mul( rest, vhi ) );
		sere_vf off = sere_vf_sub( len, target );
		sere_vmask violated = sere_vmask_and( sere_vmask_first( lanes ), sere_vf_ne( off, zero ) );
		const int32_t off_lanes = sere_vmask_count( violated );
		if ( off_lanes == 0 )
		{
			continue;
		}
		n += off_lanes;
		worst = fmaxf( worst, sere_vf_max_where( violated, sere_vf_div( sere_vf_abs( off ), rest ) ) );
		sere_vf w = sere_vf_add( wa, wb );
		sere_vmask move = sere_vmask_and( sere_vmask_and( violated, sere_vf_gt( w, zero ) ), sere_vf_gt( len, zero ) );
		sere_vf scale = sere_vf_keep( move, sere_vf_div( off, sere_vf_mul( sere_vf_mul( len, vdt ), w ) ) );
		sere_vf sa_ = sere_vf_mul( wa, scale ), sb_ = sere_vf_mul( wb, scale );
		sere_vf_store_records( vr, ia, lanes, sere_vf_add( avx, sere_vf_mul( sa_, px ) ),
							   sere_vf_add( avy, sere_vf_mul( sa_, py ) ), sere_vf_add( avz, sere_vf_mul( sa_, pz ) ),
							   avw );
		sere_vf_store_records( vr, ib, lanes, sere_vf_sub( bvx, sere_vf_mul( sb_, px ) ),
							   sere_vf_sub( bvy, sere_vf_mul( sb_, py ) ), sere_vf_sub( bvz, sere_vf_mul( sb_, pz ) ),
							   bvw );
	}
	if ( touch )
	{
		worst = fmaxf( worst, sere_vf_max_where( sere_vmask_first( SERE_LANES ), touched ) );
	}
	*worst_io = worst;
	*off_band += n;
}

/* This thread's share of the structural springs' extremes after the step, with p = x_ab + v_ab Δt
 * computed exactly as the position update will compute it: the largest excess of |p|/L beyond
 * [1 − τ, 1 + τ] (≤ 0 when all are inside) and the largest | |p|/L − 1 |. With touch, the largest
 * sum of the loaded values instead (the floor). */
static void band_measure( const sere_massspring* ms, float keep, float tau, float dt, bool touch, float* excess_out,
						  float* strain_out )
{
	const int32_t* restrict sa = ms->a;
	const int32_t* restrict sb = ms->b;
	const float* restrict rest0 = ms->rest0;
	const float* restrict xr = ms->xrec;
	const float* restrict vr = ms->vrec;
	float excess = -1.0f, strain = 0.0f;
	const int32_t count = ms->structural_count;
	const int32_t chunks = ( count + SERE_LANES - 1 ) / SERE_LANES;
	const sere_vf vkeep = sere_vf_splat( keep ), vdt = sere_vf_splat( dt ), one = sere_vf_splat( 1.0f );
	const sere_vf hi = sere_vf_splat( 1.0f + tau ), lo = sere_vf_splat( 1.0f - tau );
#pragma omp for schedule( static )
	for ( int32_t chunk = 0; chunk < chunks; ++chunk )
	{
		const int32_t s = SERE_LANES * chunk;
		int32_t ia[SERE_LANES], ib[SERE_LANES];
		const int32_t lanes = chunk_ends( sa, sb, s, count - s, ia, ib );
		const sere_vmask m = sere_vmask_first( lanes );
		sere_vf ax, ay, az, aw, bx, by, bz, bw, avx, avy, avz, bvx, bvy, bvz, unused;
		sere_vf_load_records( xr, ia, &ax, &ay, &az, &aw );
		sere_vf_load_records( xr, ib, &bx, &by, &bz, &bw );
		sere_vf_load_records( vr, ia, &avx, &avy, &avz, &unused );
		sere_vf_load_records( vr, ib, &bvx, &bvy, &bvz, &unused );
		if ( touch )
		{
			sere_vf r = sere_vf_add( sere_vf_load_first( rest0 + s, lanes, 1.0f ), sere_vf_add( aw, bw ) );
			sere_vf sum = sere_vf_add( sere_vf_add( sum4( ax, bx, avx, bvx ), r ),
									   sere_vf_add( sum4( ay, by, avy, bvy ), sum4( az, bz, avz, bvz ) ) );
			excess = fmaxf( excess, sere_vf_max_where( m, sum ) );
			continue;
		}
		sere_vf px =
			sere_vf_sub( sere_vf_add( bx, sere_vf_mul( bvx, vdt ) ), sere_vf_add( ax, sere_vf_mul( avx, vdt ) ) );
		sere_vf py =
			sere_vf_sub( sere_vf_add( by, sere_vf_mul( bvy, vdt ) ), sere_vf_add( ay, sere_vf_mul( avy, vdt ) ) );
		sere_vf pz =
			sere_vf_sub( sere_vf_add( bz, sere_vf_mul( bvz, vdt ) ), sere_vf_add( az, sere_vf_mul( avz, vdt ) ) );
		sere_vf ratio = sere_vf_div( sere_vf_norm3( px, py, pz ),
									 sere_vf_mul( sere_vf_load_first( rest0 + s, lanes, 1.0f ), vkeep ) );
		sere_vf out = sere_vf_max( sere_vf_sub( ratio, hi ), sere_vf_sub( lo, ratio ) );
		excess = fmaxf( excess, sere_vf_max_where( m, out ) );
		strain = fmaxf( strain, sere_vf_max_where( m, sere_vf_abs( sere_vf_sub( ratio, one ) ) ) );
	}
	*excess_out = excess;
	*strain_out = strain;
}

/* One strain-limiting sweep, this thread's share: the bands, then the even cuts, then the odd ones
 * (items [0, R), [R, R + E), [R + E, 2R − 1)); within a phase the items share no particle, and
 * each phase ends at the barrier of its omp for. */
static void limit_sweep( sere_massspring* ms, float keep, float lo_factor, float hi_factor, float dt, bool touch,
						 float* worst_io, int32_t* off_band )
{
	const int32_t bands = ms->band_count, colors = ms->color_count, even = bands / 2;
	const int32_t phase_start[4] = { 0, bands, bands + even, 2 * bands - 1 };
	for ( int phase = 0; phase < 3; ++phase )
	{
#pragma omp for schedule( static )
		for ( int32_t item = phase_start[phase]; item < phase_start[phase + 1]; ++item )
		{
			for ( int32_t c = 0; c < colors; ++c )
			{
				const int32_t* run = ms->run_offsets + item * colors + c;
				limit_run( ms, run[0], run[1] - run[0], keep, lo_factor, hi_factor, dt, touch, worst_io, off_band );
			}
		}
	}
}

/* Every particle finite and no inverse mass negative. */
static sere_status check_particles( const sere_massspring_particles* p, int32_t threads )
{
	int bad = 0, negative = 0;
#pragma omp parallel for num_threads( sere_team_for( threads ) ) schedule( static ) reduction( | : bad, negative )
	for ( int32_t i = 0; i < p->count; ++i )
	{
		bad |= !isfinite( p->x[i] ) | !isfinite( p->y[i] ) | !isfinite( p->z[i] ) | !isfinite( p->vx[i] ) |
			   !isfinite( p->vy[i] ) | !isfinite( p->vz[i] ) | !isfinite( p->inv_m[i] );
		negative |= p->inv_m[i] < 0.0f;
	}
	if ( bad )
	{
		return SERE_ERR_NONFINITE;
	}
	return negative ? SERE_ERR_ARGUMENT : SERE_OK;
}

/* The velocities the sweeps left (in the packed records) become the particles', and the
 * particles move by them (Tang Eq. 1: x ← x + v Δt with the new v). Called inside the parallel
 * region: its loop is shared among the team. */
static void advance_positions( const sere_massspring* ms, sere_massspring_particles* p, float dt )
{
	const float* restrict vr = ms->vrec;
#pragma omp for schedule( static )
	for ( int32_t i = 0; i < p->count; ++i )
	{
		p->vx[i] = vr[4 * i];
		p->vy[i] = vr[4 * i + 1];
		p->vz[i] = vr[4 * i + 2];
		p->x[i] = p->x[i] + vr[4 * i] * dt;
		p->y[i] = p->y[i] + vr[4 * i + 1] * dt;
		p->z[i] = p->z[i] + vr[4 * i + 2] * dt;
	}
}

sere_status sere_massspring_step( sere_massspring* ms, sere_massspring_particles* p,
								  const sere_massspring_params* params, sere_massspring_report* report )
{
	if ( ms == NULL || p == NULL || params == NULL || p->count != ms->vertex_count || p->x == NULL || p->y == NULL ||
		 p->z == NULL || p->vx == NULL || p->vy == NULL || p->vz == NULL || p->inv_m == NULL ||
		 !params_valid( params ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	sere_status status = check_particles( p, ms->threads );
	if ( status != SERE_OK )
	{
		return status;
	}

	const float keep = 1.0f - params->shrink;
	const spring_law structural = { keep, params->stiffness, params->damping };
	const spring_law flexion = { 1.0f - params->curl, params->bend_stiffness, params->damping };
	const float dt = params->dt, tau = params->strain_limit, tolerance = params->strain_tolerance;
	/* The sweeps aim at the band narrowed by the tolerance on both sides, so that once no
	 * spring is off that inner band by more than the tolerance, all are inside the true band. */
	const float inner_lo = 1.0f - tau + tolerance, inner_hi = 1.0f + tau - tolerance;
	float sweep_worst = 0.0f, excess = 0.0f, final_strain = 0.0f;
	int32_t sweeps = 0, limited = 0, sweep_limited = 0;
	int converged = 0;

#pragma omp parallel num_threads( sere_team_for( ms->threads ) )
	{
		pack( ms, p );
		spring_forces( ms, 0, ms->structural_count, structural, false );
		spring_forces( ms, ms->structural_count, ms->flexion_count, flexion, false );
		integrate_velocities( ms, p->count, params );

		for ( int32_t sweep = 0; sweep < params->max_sweeps; ++sweep )
		{
#pragma omp single
			{
				sweep_worst = 0.0f;
				sweep_limited = 0;
				excess = -1.0f;
				final_strain = 0.0f;
			}
			float mine = 0.0f;
			int32_t mine_limited = 0;
			limit_sweep( ms, keep, inner_lo, inner_hi, dt, false, &mine, &mine_limited );
			/* A maximum and an integer sum: the same in any order of the threads. */
#pragma omp critical( sere_massspring_worst )
			{
				sweep_worst = fmaxf( sweep_worst, mine );
				sweep_limited += mine_limited;
			}
#pragma omp barrier
			/* Every thread reads the same values, so every thread takes the same branches. A
			 * sweep's corrections can nudge springs it limited earlier, so a quiet sweep is
			 * confirmed by measuring the true band before stopping. */
			int done = sweep_worst <= tolerance;
			if ( done )
			{
				float own_excess, own_strain;
				band_measure( ms, keep, tau, dt, false, &own_excess, &own_strain );
#pragma omp critical( sere_massspring_worst )
				{
					excess = fmaxf( excess, own_excess );
					final_strain = fmaxf( final_strain, own_strain );
				}
#pragma omp barrier
				done = excess <= 0.0f;
			}
#pragma omp single
			{
				sweeps = sweep + 1;
				if ( sweep == 0 )
				{
					limited = sweep_limited;
				}
				converged = done;
			}
			if ( done )
			{
				break;
			}
		}
		if ( !converged )
		{
			float own_excess, own_strain;
			band_measure( ms, keep, tau, dt, false, &own_excess, &own_strain );
#pragma omp critical( sere_massspring_worst )
			final_strain = fmaxf( final_strain, own_strain );
		}

		advance_positions( ms, p, dt );
	}

	if ( report != NULL )
	{
		report->sweeps = sweeps;
		report->limited = limited;
		report->max_strain = final_strain;
		report->hit_cap = !converged;
	}
	return converged ? SERE_OK : SERE_ERR_NO_CONVERGE;
}

sere_status sere_massspring_touch( sere_massspring* ms, sere_massspring_particles* p, int32_t sweeps )
{
	if ( ms == NULL || p == NULL || p->count != ms->vertex_count || p->x == NULL || p->y == NULL || p->z == NULL ||
		 p->vx == NULL || p->vy == NULL || p->vz == NULL || p->inv_m == NULL || sweeps < 1 )
	{
		return SERE_ERR_ARGUMENT;
	}
	sere_status status = check_particles( p, ms->threads );
	if ( status != SERE_OK )
	{
		return status;
	}
	/* Δt = 0, no drag and no gravity: the integration and the position update run as in a step and
	 * leave every particle where it was. */
	sere_massspring_params still = sere_massspring_params_default();
	still.dt = 0.0f;
	still.drag = 0.0f;
	still.gravity[2] = 0.0f;
	const spring_law none = { 1.0f, 0.0f, 0.0f };
	float sink = 0.0f;
#pragma omp parallel num_threads( sere_team_for( ms->threads ) )
	{
		pack( ms, p );
		spring_forces( ms, 0, ms->structural_count, none, true );
		spring_forces( ms, ms->structural_count, ms->flexion_count, none, true );
		integrate_velocities( ms, p->count, &still );
		float mine = 0.0f;
		int32_t unused = 0;
		for ( int32_t sweep = 0; sweep < sweeps; ++sweep )
		{
			limit_sweep( ms, 1.0f, 0.0f, 0.0f, 0.0f, true, &mine, &unused );
			/* the step's reduction and barrier after each sweep */
#pragma omp critical( sere_massspring_worst )
			sink = fmaxf( sink, mine );
#pragma omp barrier
		}
		float own_excess, own_strain;
		band_measure( ms, 1.0f, 0.0f, 0.0f, true, &own_excess, &own_strain );
#pragma omp critical( sere_massspring_worst )
		sink = fmaxf( sink, own_excess );
		advance_positions( ms, p, 0.0f );
	}
	ms->touch_sink = sink;
	return SERE_OK;
}
