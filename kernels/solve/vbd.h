/* sere — the implicit step of distance springs solved as a descent (vertex block descent, Chen et
 * al. 2024): the position that minimizes the step's energy
 *
 *   E(x) = ½ Σ_i m_i |x_i − x̃_i|² + Σ_j (|x_a − x_b| − l_j)² / (2 α̃_j),   α̃_j = α w_j / dt²,
 *
 * the energy XPBD's step is derived from (Macklin et al. 2016, Eqs. 6–9), x̃ the prediction. Where
 * XPBD drives the constraints to their compliant values and leaves the force balance to hold as
 * long as the springs keep their directions (docs/DESIGN.md §8), this solver makes ∂E/∂x_i = 0 at
 * every particle: each sweep moves every particle by one Newton step on its own 3 × 3 block of E,
 * the others held, particles of one color (no spring between them) at once.
 *
 * Works on plain index / rest-length / position arrays, like solve/pbd.h, and knows nothing of
 * leaves. A frame is: sere_vbd_set_rest (when rest lengths changed), the prediction
 * (sere_pbd_predict), sere_vbd_step, sere_pbd_finish. */
#pragma once

#include "core/base.h"

#ifdef __cplusplus
extern "C"
{
#endif

typedef struct sere_vbd_params
{
	float dt;				/* time step, > 0 */
	float compliance;		/* α > 0: spring j has stiffness 1/α̃_j = dt² / (α w_j) */
	float tolerance;		/* stop when no particle moved farther than this in a sweep (length units), > 0 */
	int32_t max_iterations; /* sweep cap, ≥ 1 */
	/* Chebyshev semi-iteration of the sweeps (Wang 2015, as sere_pbd_params): ρ ∈ [0, 1), 0 off.
	 * After sweep k > delay the positions become ω_k (x̂_k − x_{k−2}) + x_{k−2}, x̂_k the sweep's
	 * result, ω_{delay+1} = 2/(2 − ρ²), ω_k = 4/(4 − ρ² ω_{k−1}). Descent steps keep one answer
	 * (E's minimum near the prediction), so the extrapolation changes how fast, not where. */
	float chebyshev_rho;
	int32_t chebyshev_delay; /* plain sweeps before the first extrapolation, ≥ 2 */
	/* A ground plane z ≥ ground (−INFINITY: none), a bound of the descent: a particle's Newton step
	 * that ends below it ends on it instead. sere_vbd_ground_push reports the ground's reaction on
	 * the particles it held in the last sweep as a displacement, ∂E/∂z_i / m_i at the start of the
	 * particle's step (the bound's multiplier over the mass): the normal correction d_n that
	 * position-based Coulomb friction bounds the sliding by (Macklin et al. 2014, Sec. 6.1). */
	float ground;
	/* 1: begin the sweeps at the prediction plus the last successful step's correction (its answer
	 * less its prediction) rather than at the prediction; 0 (the default): at the prediction. */
	int32_t warm_start;
} sere_vbd_params;

/* dt = 0.002 (Table 2), α = 4e-6 (the leaf's XPBD compliance), tolerance 1e-6, 200 sweeps,
 * no Chebyshev (delay 5 when turned on), no ground, no warm start. */
sere_vbd_params sere_vbd_params_default( void );

typedef struct sere_vbd_report
{
	int32_t iterations; /* sweeps run */
	float max_move;		/* the largest move of a particle in the last sweep */
	/* the stop used: params->tolerance, or FLT_EPSILON times the largest |coordinate| when that is
	 * larger (a sweep cannot move a particle by less than its coordinates' rounding) */
	float tolerance;
	int hit_cap; /* stopped by max_iterations, not by the tolerance */
} sere_vbd_report;

typedef struct sere_vbd_info
{
	int32_t colors;	 /* colors of the particle graph (no spring inside a color) */
	int32_t blocks;	 /* blocks of SERE_LANES particles of one color */
	int32_t entries; /* spring slots swept per sweep: each block's lanes times its largest degree */
	int32_t springs; /* spring ends (2 per spring): entries − springs is the padding */
} sere_vbd_info;

typedef struct sere_vbd sere_vbd;

/* Builds the workspace for springs (a[i], b[i]) over particles [0, particle_count): colors the
 * particles greedily in index order, sorts each color's particles by degree (so the lanes of a
 * block sweep alike many springs), cuts them into blocks of SERE_LANES and lays out, per block,
 * each lane's springs in the order a sweep reads them. Everything a step needs is allocated
 * here. SERE_ERR_ARGUMENT for an index out of range or a spring joining a particle to itself,
 * SERE_ERR_CAPACITY past 64 colors, SERE_ERR_MEMORY. */
sere_status sere_vbd_create( const int32_t* a, const int32_t* b, int32_t spring_count, int32_t particle_count,
							 sere_vbd** out );
void sere_vbd_destroy( sere_vbd* vbd );
sere_vbd_info sere_vbd_get_info( const sere_vbd* vbd );

/* Copies the rest lengths (indexed like the springs given to create). SERE_ERR_GEOMETRY for one
 * that is not positive and finite; steps are then refused until a valid set is given. */
sere_status sere_vbd_set_rest( sere_vbd* vbd, const float* rest );

/* Per-spring compliance weights w_j (indexed like the springs; NULL: 1 everywhere, the default).
 * SERE_ERR_ARGUMENT for a weight that is not positive and finite (a descent needs every spring's
 * stiffness finite), leaving the previous weights. */
sere_status sere_vbd_set_compliance_weights( sere_vbd* vbd, const float* weight );

/* The threads a step runs on (core/base.h; steps run on one thread while the team's sweeps have
 * been measured slower). SERE_ERR_ARGUMENT above SERE_MAX_THREADS. */
sere_status sere_vbd_set_threads( sere_vbd* vbd, int32_t threads );

/* Minimizes E for the prediction px, py, pz (x̃ = the positions passed in), in place, until a
 * sweep moves no particle farther than params->tolerance (or the rounding of the coordinates,
 * report->tolerance), or the cap. The sweeps begin at x̃, or with params->warm_start at x̃ plus
 * the last step's correction (its answer less its prediction; at x̃ before any step has
 * succeeded): E and so its minimum stay the same, only the sweeps' start moves, and it keeps
 * the same bits at every thread count. Particles with inv_m = 0 are held and take any force;
 * m_i = 1/inv_m otherwise.
 *
 * A particle's step solves H_i Δ = −∂E/∂x_i with H_i = m_i I + Σ_j k_j [ n nᵀ + β (I − n nᵀ) ],
 * n the spring's direction and β = max(0, 1 − l/|d|): a compressed spring's bending part is left
 * out, which keeps H_i positive definite (the reference twin, ref/vbd_ref.h, clamps it the same
 * way). Colors run one after another; a color's blocks are shared among the threads, each thread's blocks on cache
 * lines of their own; a particle reads only particles of other colors, so every thread count gives the same bits.
 *
 * Errors: SERE_ERR_NONFINITE for NaN or infinite positions or inverse masses, or positions that
 * overflow during the sweeps; SERE_ERR_GEOMETRY without valid rest lengths; SERE_ERR_ARGUMENT
 * for a negative inverse mass, a NULL pointer or a parameter out of range. On any error px, py,
 * pz are left as they were. */
sere_status sere_vbd_step( sere_vbd* vbd, float* px, float* py, float* pz, const float* inv_m,
						   const sere_vbd_params* params, sere_vbd_report* report );

/* Adds to push[i] the ground's reaction on particle i in the last sweep of the last step, as a
 * displacement (sere_vbd_params.ground; 0 where the ground did not hold it, and everywhere when
 * the last step was refused or had no ground). */
sere_status sere_vbd_ground_push( const sere_vbd* vbd, float* push );

/* How far positions px, py, pz are from a rest state of E for the prediction tx, ty, tz: over the
 * particles with inv_m > 0 and above the ground (a bound's reaction is no spring force),
 * primal = ‖∂E/∂x‖₂, inertia = ‖M (x − x̃)‖₂ and constraint = ‖spring forces‖₂; the same norms
 * sere_pbd_step_residual takes of an XPBD answer, whose multipliers at E's minimum are
 * λ_j = −C_j/α̃_j. Serial, in double, in particle order. SERE_ERR_ARGUMENT for a NULL pointer
 * or parameters a step would refuse, SERE_ERR_GEOMETRY without valid rest lengths. */
typedef struct sere_vbd_residuals
{
	double primal, inertia, constraint;
	int32_t particles;
} sere_vbd_residuals;

sere_status sere_vbd_step_residual( const sere_vbd* vbd, const float* px, const float* py, const float* pz,
									const float* tx, const float* ty, const float* tz, const float* inv_m,
									const sere_vbd_params* params, sere_vbd_residuals* out );

/* `sweeps` sweeps of sere_vbd_step's schedule with the same loads and stores (own records,
 * masses, prediction, each lane's neighbours' records and its springs' lengths and stiffnesses),
 * the Newton step replaced by a sum: the memory floor of a step of that many sweeps, for
 * benchmarks. Leaves px, py, pz unchanged. SERE_ERR_ARGUMENT for sweeps < 1 or a NULL pointer. */
sere_status sere_vbd_touch_sweeps( sere_vbd* vbd, float* px, float* py, float* pz, const float* inv_m, int32_t sweeps );

#ifdef __cplusplus
}
#endif
