/* sere — Wilting (Sec. 6, Lu Eq. 1): posing the skeleton and skinning the mesh. Seed 003: Lu, Zhao, Guo 2009. */
/* _GNU_SOURCE: sched_getaffinity for core/internal/team.h. */
#define _GNU_SOURCE

#include "wilt/internal/skeleton_shared.h"

#include "core/internal/simd.h"
#include "core/internal/team.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* ---------------------------------------------------------------------------------------------
 * Wilting (Sec. 6, Lu Eq. 1). */

sere_wilt_params sere_wilt_params_default( void )
{
	sere_wilt_params p;
	p.droop_max = INFINITY;
	p.min_angle = (float) ( 120.0 * PI / 180.0 );
	p.spread = 0.5f;
	p.pierce_margin = 1e-3f;
	p.pierce = 1;
	return p;
}

void sere_joint_frames_destroy( sere_joint_frames* frames )
{
	sere_free( frames->x );
	sere_free( frames->y );
	sere_free( frames->z );
	for ( int k = 0; k < 9; ++k )
	{
		sere_free( frames->m[k] );
	}
	sere_free( frames->work );
	memset( frames, 0, sizeof( *frames ) );
}

sere_status sere_joint_frames_create( sere_joint_frames* frames, int32_t joint_count )
{
	memset( frames, 0, sizeof( *frames ) );
	if ( joint_count < 1 || joint_count > ( 1 << 24 ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	size_t n = (size_t) sere_pad( joint_count );
	int failed = 0;
	frames->x = sere_alloc( n * sizeof( float ) );
	frames->y = sere_alloc( n * sizeof( float ) );
	frames->z = sere_alloc( n * sizeof( float ) );
	failed |= frames->x == NULL || frames->y == NULL || frames->z == NULL;
	for ( int k = 0; k < 9; ++k )
	{
		frames->m[k] = sere_alloc( n * sizeof( float ) );
		failed |= frames->m[k] == NULL;
	}
	frames->work = sere_alloc( 12 * n * sizeof( double ) );
	if ( failed || frames->work == NULL )
	{
		sere_joint_frames_destroy( frames );
		return SERE_ERR_MEMORY;
	}
	frames->capacity = (int32_t) n;
	return SERE_OK;
}

/* A turn in [0, π] as its cosine and sine (s ≥ 0). Every limit of Sec. 6 comes as a ratio of
 * lengths and the rotation needs only the cosine and sine, so turns are compared and applied in
 * this form, without an arc function: acos, atan2 and the sine and cosine of their difference
 * were 70% of a pose (posing is the chain of each leaf's joints, which no vector hides). */
typedef struct turn
{
	double c, s;
} turn;

/* Whether turn x is smaller than turn y: sin(y − x) > 0, which keeps its sign where the cosines
 * of two small turns would round alike; at a sine of 0 (0 against π) the larger cosine is the
 * smaller turn. */
static int turn_before( turn x, turn y )
{
	double d = x.c * y.s - x.s * y.c;
	return d > 0.0 || ( d == 0.0 && x.c > y.c );
}

/* Rotation by turn t about the unit axis n (Rodrigues), row-major. */
static void axis_rotation( const double n[3], turn t, double r[9] )
{
	double c = t.c, s = t.s, k = 1.0 - c;
	r[0] = c + k * n[0] * n[0];
	r[1] = k * n[0] * n[1] - s * n[2];
	r[2] = k * n[0] * n[2] + s * n[1];
	r[3] = k * n[1] * n[0] + s * n[2];
	r[4] = c + k * n[1] * n[1];
	r[5] = k * n[1] * n[2] - s * n[0];
	r[6] = k * n[2] * n[0] - s * n[1];
	r[7] = k * n[2] * n[1] + s * n[0];
	r[8] = c + k * n[2] * n[2];
}

static void mat_mul( const double a[9], const double b[9], double out[9] )
{
	for ( int r = 0; r < 3; ++r )
	{
		for ( int c = 0; c < 3; ++c )
		{
			out[3 * r + c] = a[3 * r] * b[c] + a[3 * r + 1] * b[3 + c] + a[3 * r + 2] * b[6 + c];
		}
	}
}

/* Shortens *phi to the largest turn such that f(ψ) = a cos ψ + b sin ψ stays ≥ h for ψ in
 * [0, *phi], and says whether it did. With f = R cos(ψ − β), β = atan2(b, a), the feasible
 * phases are |ψ − β| ≤ γ = acos(h / R); ψ leaves them at β + γ, whose cosine and sine are
 * (a h − b S) / R² and (b h + a S) / R² with S = √(R² − h²). At h ≥ R, or at a start just
 * outside (rounding at a limit reached by an earlier joint) that is falling (β + γ < 0: β < 0
 * and a < h), the exit is 0; a start outside that is rising is let through. An exit past π
 * (a negative sine while rising, β > 0) is beyond any turn. */
static int exit_before( double a, double b, double h, turn* phi )
{
	double rr = a * a + b * b;
	if ( h <= 0.0 && h * h >= rr )
	{
		return 0; /* h ≤ −R: f never falls below h */
	}
	turn exit = { 1.0, 0.0 };
	if ( h * h < rr && !( signbit( b ) && a < h ) )
	{
		double root = sqrt( rr - h * h );
		exit = ( turn ){ ( a * h - b * root ) / rr, ( b * h + a * root ) / rr };
		if ( exit.s < 0.0 )
		{
			/* past π when rising, else a rounding of an exit at 0 */
			if ( !signbit( b ) )
			{
				return 0;
			}
			exit = ( turn ){ 1.0, 0.0 };
		}
	}
	if ( !turn_before( exit, *phi ) )
	{
		return 0;
	}
	*phi = exit;
	return 1;
}

enum
{
	LIMIT_NONE,
	LIMIT_DOWN,
	LIMIT_ANGLE,
	LIMIT_DROOP
};

/* Minimal angle (Sec. 6): shortens *phi to the largest turn that keeps the included angle between
 * the segment g → p (as posed) and the turning segment p → i at least min_angle, cos_limit being
 * −cos(min_angle), and says whether it did. u is the segment p → i before the turn, n the
 * turning axis. */
static int angle_limited_turn( const double* pg, const double* pp, const double u[3], double length, const double n[3],
							   double cos_limit, turn* phi )
{
	double w[3] = { pp[0] - pg[0], pp[1] - pg[1], pp[2] - pg[2] };
	double wl = sqrt( w[0] * w[0] + w[1] * w[1] + w[2] * w[2] );
	double uh[3] = { u[0] / length, u[1] / length, u[2] / length };
	double e[3] = { n[1] * uh[2], -n[0] * uh[2], n[0] * uh[1] - n[1] * uh[0] };
	double a = ( w[0] * uh[0] + w[1] * uh[1] + w[2] * uh[2] ) / wl;
	double b = ( w[0] * e[0] + w[1] * e[1] + w[2] * e[2] ) / wl;
	return exit_before( a, b, cos_limit, phi );
}

/* Maximal droop (Sec. 6): every joint k of the subtree of i turns rigidly about the horizontal
 * axis n through P_p: z_k(φ) = z_p + a cos φ + b sin φ must stay ≥ z_k^rest − droop_max. Shortens
 * *phi to the largest turn that keeps it and says whether it did. */
static int droop_limited_turn( const sere_skeleton* s, int32_t i, int32_t p, const double* pp, const double* qp,
							   const double n[3], double droop_max, turn* phi )
{
	int limited = 0;
	for ( int32_t k = i; k < s->end[i]; ++k )
	{
		double v0[3] = { (double) s->x[k] - s->x[p], (double) s->y[k] - s->y[p], (double) s->z[k] - s->z[p] };
		double v[3];
		sere_skel_mat_vec( qp, v0, v );
		double b = n[0] * v[1] - n[1] * v[0];
		limited |= exit_before( v[2], b, (double) s->z[k] - droop_max - pp[2], phi );
	}
	return limited;
}

/* The rotation r (Rodrigues, about n = u × d / |u × d|) that turns segment p → i, currently u,
 * by its target angle phi toward d = (0, 0, −1), shortened by the limits of Sec. 6; counts the
 * turn and its limit in st. Returns whether the segment turns (r is left alone when not). */
static int segment_rotation( const sere_skeleton* s, const double* work, int32_t i, const double u[3], double phi,
							 double cos_limit, const sere_wilt_params* params, double r[9], sere_pose_stats* st )
{
	int32_t p = s->parent[i];
	const double* pp = work + 12 * (size_t) p;
	double length = sqrt( u[0] * u[0] + u[1] * u[1] + u[2] * u[2] );
	double horizontal = sqrt( u[0] * u[0] + u[1] * u[1] );
	/* A vertical segment has no plane with d: pointing down it is done, pointing up it waits. */
	if ( !( phi > 0.0 && horizontal > 1e-12 * length ) )
	{
		return 0;
	}
	++st->turning;
	int limit = LIMIT_NONE;
	/* n = u × d / |u × d| with d = (0, 0, −1): horizontal, so the segment swings in the
	 * vertical plane through it and d (Fig. 4a). */
	double n[3] = { -u[1] / horizontal, u[0] / horizontal, 0.0 };
	/* Lu Eq. 1 runs φ up to the angle Ω between u and d, where the segment points straight
	 * down. */
	turn omega = { -u[2] / length, horizontal / length }, turn_phi = omega;
	/* a target at or past π (where its sine would turn negative) is past Ω: the segment points
	 * down */
	if ( phi < PI )
	{
		turn_phi = ( turn ){ cos( phi ), sin( phi ) };
	}
	if ( !turn_before( turn_phi, omega ) )
	{
		turn_phi = omega;
		limit = LIMIT_DOWN;
	}
	int32_t g = s->parent[p];
	if ( params->min_angle > 0.0f && g >= 0 && s->vein[p] == s->vein[i] &&
		 angle_limited_turn( work + 12 * (size_t) g, pp, u, length, n, cos_limit, &turn_phi ) )
	{
		limit = LIMIT_ANGLE;
	}
	if ( isfinite( params->droop_max ) && droop_limited_turn( s, i, p, pp, pp + 3, n, params->droop_max, &turn_phi ) )
	{
		limit = LIMIT_DROOP;
	}
	st->down_limited += limit == LIMIT_DOWN;
	st->angle_limited += limit == LIMIT_ANGLE;
	st->droop_limited += limit == LIMIT_DROOP;
	axis_rotation( n, turn_phi, r );
	return 1;
}

/* The frames of joints [first, first + count) from their posed positions and rotations in work,
 * rounded to float. */
static void frames_store( sere_joint_frames* frames, int32_t first, int32_t count )
{
	for ( int32_t i = first; i < first + count; ++i )
	{
		const double* pi = frames->work + 12 * (size_t) i;
		frames->x[i] = (float) pi[0];
		frames->y[i] = (float) pi[1];
		frames->z[i] = (float) pi[2];
		for ( int k = 0; k < 9; ++k )
		{
			frames->m[k][i] = (float) pi[3 + k];
		}
	}
}

void sere_skel_pose_range( const sere_skeleton* s, int32_t first, int32_t count, float t,
						   const sere_wilt_params* params, sere_joint_frames* frames, uint8_t* turned,
						   sere_pose_stats* stats )
{
	double* work = frames->work;
	double spread = params->spread;
	double progress_scale = 1.0 / ( 1.0 - spread );
	double cos_limit = -cos( (double) params->min_angle ); /* Sec. 6: included angle ≥ min_angle */
	sere_pose_stats st = { 0, 0, 0, 0 };
	for ( int32_t i = first; i < first + count; ++i )
	{
		double* pi = work + 12 * (size_t) i;
		double* qi = pi + 3;
		int32_t p = s->parent[i];
		if ( p < 0 )
		{
			pi[0] = s->x[i];
			pi[1] = s->y[i];
			pi[2] = s->z[i];
			memset( qi, 0, 9 * sizeof( double ) );
			qi[0] = qi[4] = qi[8] = 1.0;
			if ( turned != NULL )
			{
				turned[i] = 0;
			}
			continue;
		}
		const double* pp = work + 12 * (size_t) p;
		const double* qp = pp + 3;
		/* The segment p → i as its ancestors' rotations left it. */
		double u0[3] = { (double) s->x[i] - s->x[p], (double) s->y[i] - s->y[p], (double) s->z[i] - s->z[p] };
		double u[3];
		sere_skel_mat_vec( qp, u0, u );
		/* Sec. 7: the joint's target angle grows with the wilting parameter t after its onset. */
		double progress = ( t - spread * s->delay[i] ) * progress_scale;
		progress = progress < 0.0 ? 0.0 : ( progress > 1.0 ? 1.0 : progress );
		double phi = s->bend[i] * progress;
		double r[9] = { 1, 0, 0, 0, 1, 0, 0, 0, 1 };
		int turns = segment_rotation( s, work, i, u, phi, cos_limit, params, r, &st );
		if ( turned != NULL )
		{
			turned[i] = (uint8_t) turns;
		}
		/* Lu Eq. 1: P(φ) = P_p + |u| (cos φ û + sin φ ê) with ê = n × û, here as P_p + R u. */
		double v[3];
		sere_skel_mat_vec( r, u, v );
		pi[0] = pp[0] + v[0];
		pi[1] = pp[1] + v[1];
		pi[2] = pp[2] + v[2];
		mat_mul( r, qp, qi );
	}
	frames_store( frames, first, count );
	if ( stats != NULL )
	{
		*stats = st;
	}
}

sere_status sere_skel_check_wilt_params( const sere_wilt_params* p )
{
	if ( p == NULL )
	{
		return SERE_ERR_ARGUMENT;
	}
	if ( isnan( p->droop_max ) || !isfinite( p->min_angle ) || !isfinite( p->spread ) || !isfinite( p->pierce_margin ) )
	{
		return SERE_ERR_NONFINITE;
	}
	if ( p->droop_max < 0.0f || p->min_angle < 0.0f || p->min_angle > (float) PI || p->spread < 0.0f ||
		 !( p->spread < 1.0f ) || p->pierce_margin < 0.0f )
	{
		return SERE_ERR_ARGUMENT;
	}
	return SERE_OK;
}

/* The checks of a pose's arguments but t. */
static sere_status pose_inputs( const sere_skeleton* skeleton, int32_t first, int32_t count,
								const sere_wilt_params* params, const sere_joint_frames* frames )
{
	sere_status status = sere_skel_check_wilt_params( params );
	if ( status != SERE_OK )
	{
		return status;
	}
	if ( skeleton == NULL || frames == NULL || first < 0 || count < 1 || first > skeleton->joint_count - count ||
		 frames->capacity < first + count || skeleton->parent[first] != -1 || skeleton->end[first] != first + count )
	{
		return SERE_ERR_ARGUMENT;
	}
	return SERE_OK;
}

/* A pose, recording which segments turn when turned is not NULL. */
static sere_status pose( const sere_skeleton* skeleton, int32_t first, int32_t count, float t,
						 const sere_wilt_params* params, sere_joint_frames* frames, uint8_t* turned,
						 sere_pose_stats* stats )
{
	sere_status status = pose_inputs( skeleton, first, count, params, frames );
	if ( status != SERE_OK )
	{
		return status;
	}
	if ( !isfinite( t ) )
	{
		return SERE_ERR_NONFINITE;
	}
	t = t < 0.0f ? 0.0f : ( t > 1.0f ? 1.0f : t );
	sere_skel_pose_range( skeleton, first, count, t, params, frames, turned, stats );
	return SERE_OK;
}

sere_status sere_skeleton_pose( const sere_skeleton* skeleton, int32_t first, int32_t count, float t,
								const sere_wilt_params* params, sere_joint_frames* frames, sere_pose_stats* stats )
{
	return pose( skeleton, first, count, t, params, frames, NULL, stats );
}

sere_status sere_skeleton_record_pose( const sere_skeleton* skeleton, int32_t first, int32_t count, float t,
									   const sere_wilt_params* params, sere_joint_frames* frames, uint8_t* turned,
									   sere_pose_stats* stats )
{
	return turned == NULL ? SERE_ERR_ARGUMENT : pose( skeleton, first, count, t, params, frames, turned, stats );
}

sere_status sere_skeleton_touch_pose( const sere_skeleton* s, int32_t first, int32_t count,
									  const sere_wilt_params* params, const uint8_t* turned, sere_joint_frames* frames )
{
	sere_status status = pose_inputs( s, first, count, params, frames );
	if ( status != SERE_OK || turned == NULL )
	{
		return status != SERE_OK ? status : SERE_ERR_ARGUMENT;
	}
	double* work = frames->work;
	/* A 1 and a sink the compiler cannot see through: the stores keep the values already there, and
	 * the sum of what was read (integer sums of the bits, skeleton_shared.h) is not dropped with
	 * its loads. */
	volatile double hidden_one = 1.0;
	const double one = hidden_one;
	uint64_t sum = 0;
	for ( int32_t i = first; i < first + count; ++i )
	{
		double* pi = work + 12 * (size_t) i;
		int32_t p = s->parent[i];
		uint64_t read = (uint64_t) sere_skel_float_bits( s->x[i] ) + sere_skel_float_bits( s->y[i] ) +
						sere_skel_float_bits( s->z[i] );
		if ( p >= 0 )
		{
			/* the segment's rest ends and the parent's frame, the onset and the bend */
			const double* pp = work + 12 * (size_t) p;
			read += (uint64_t) sere_skel_float_bits( s->x[p] ) + sere_skel_float_bits( s->y[p] ) +
					sere_skel_float_bits( s->z[p] ) + sere_skel_float_bits( s->delay[i] ) +
					sere_skel_float_bits( s->bend[i] );
			for ( int k = 0; k < 12; ++k )
			{
				read += sere_skel_double_bits( pp[k] );
			}
			if ( turned[i] )
			{
				/* the limits' reads: the grandparent's position when the segment continues its
				 * parent's vein, the subtree's rest positions for the droop */
				int32_t g = s->parent[p];
				if ( params->min_angle > 0.0f && g >= 0 && s->vein[p] == s->vein[i] )
				{
					const double* pg = work + 12 * (size_t) g;
					read += sere_skel_double_bits( pg[0] ) + sere_skel_double_bits( pg[1] ) +
							sere_skel_double_bits( pg[2] );
				}
				if ( isfinite( params->droop_max ) )
				{
					for ( int32_t k = i; k < s->end[i]; ++k )
					{
						read += (uint64_t) sere_skel_float_bits( s->x[k] ) + sere_skel_float_bits( s->y[k] ) +
								sere_skel_float_bits( s->z[k] );
					}
				}
			}
		}
		for ( int k = 0; k < 12; ++k )
		{
			pi[k] *= one;
		}
		sum += read;
	}
	frames_store( frames, first, count );
	volatile uint64_t sink = sum;
	(void) sink;
	return SERE_OK;
}

/* Vertices are skinned in blocks of this many; a block is the unit of parallel work. */
#define SKIN_BLOCK 2048
/* The end of the run of joint j that continues at e, at most end: a lane width of indices
 * compared at once, the first that differs found from the compare's mask. One index at a time,
 * the scan was a branch a vertex and took half the time of a skin (BM_skeleton_skin against its
 * floor); an OR of each 16 indices' differences, reduced across lanes and then searched index by
 * index, still took about 15%. */
static inline int32_t run_end( const int32_t* joint, int32_t e, int32_t end, int32_t j )
{
	while ( end - e >= SERE_LANES )
	{
		int32_t k = sere_vi_first_ne( joint + e, j );
		if ( k < SERE_LANES )
		{
			return e + k;
		}
		e += SERE_LANES;
	}
	while ( e < end && joint[e] == j )
	{
		++e;
	}
	return e;
}

void sere_joint_frames_skin( const sere_joint_frames* frames, const int32_t* joint, const float* ox, const float* oy,
							 const float* oz, int32_t vertex_count, float* x, float* y, float* z, int32_t threads )
{
	const float *px = frames->x, *py = frames->y, *pz = frames->z;
	float* const* m = frames->m;
	int32_t blocks = ( vertex_count + SKIN_BLOCK - 1 ) / SKIN_BLOCK;
	/* Rigid binding (Sec. 6): x = p_j + R_j o. Vertices of one joint that sit together (a plant
	 * orders each leaf's vertices by joint) form a run: its transform is loaded once and
	 * broadcast, and the run streams through unit-stride SIMD with no gathers. Any order is
	 * correct; scattered joints just make runs of one. */
#pragma omp parallel for num_threads( sere_team_for( threads ) ) schedule( static )
	for ( int32_t b = 0; b < blocks; ++b )
	{
		int32_t i = b * SKIN_BLOCK;
		int32_t end = i + SKIN_BLOCK < vertex_count ? i + SKIN_BLOCK : vertex_count;
		while ( i < end )
		{
			int32_t j = joint[i];
			int32_t e = run_end( joint, i + 1, end, j );
			float tx = px[j], ty = py[j], tz = pz[j];
			float m0 = m[0][j], m1 = m[1][j], m2 = m[2][j];
			float m3 = m[3][j], m4 = m[4][j], m5 = m[5][j];
			float m6 = m[6][j], m7 = m[7][j], m8 = m[8][j];
#pragma omp simd
			for ( int32_t k = i; k < e; ++k )
			{
				float a = ox[k], c = oy[k], d = oz[k];
				x[k] = tx + ( ( m0 * a + m1 * c ) + m2 * d );
				y[k] = ty + ( ( m3 * a + m4 * c ) + m5 * d );
				z[k] = tz + ( ( m6 * a + m7 * c ) + m8 * d );
			}
			i = e;
		}
	}
}
