/* sere — position-based dynamics of distance constraints (Sec. 5.2, Jeong Eq. 13), Gauss–Seidel in
 * parallel by graph coloring. Works on plain index / rest-length / position arrays and knows
 * nothing of water or leaves.
 *
 * A frame is: sere_pbd_set_rest (when rest lengths changed), sere_pbd_predict,
 * sere_pbd_project (or sere_pbd_project_jacobi), sere_pbd_finish. */
#pragma once

#include "solve/color.h"

#ifdef __cplusplus
extern "C"
{
#endif

typedef struct sere_pbd_params
{
	float stiffness;		/* k ∈ [0, 1]: the fraction of each correction applied (Sec. 5.2) */
	float tolerance;		/* λ_C > 0: stop when max |C/l| < λ_C */
	int32_t max_iterations; /* sweep cap, ≥ 1 */
	float compliance;		/* XPBD compliance α ≥ 0 (0: the paper's PBD); needs dt */
	float dt;				/* time step, for XPBD's α̃ = α/dt² */
	float relaxation;		/* ω ∈ (0, 2) of the Jacobi variant (ignored by Gauss–Seidel) */
	/* Nonzero: use k' = 1 − (1 − k)^(1/max_iterations) per sweep (Müller et al. 2007, Sec. 3.3),
	 * so that the cap's worth of sweeps removes the fraction k of the error whatever the cap.
	 * Zero (the default, the paper's mode): k is applied as given in every sweep. */
	int linear_stiffness;
	/* XPBD only. Zero (the default): the multipliers start at zero, one call = one time step.
	 * Nonzero: they continue from the previous call, so that a step interrupted to resolve
	 * contacts (a ground plane, say) goes on solving the same problem; the inertia anchor of
	 * the step stays where the first call of the step started. */
	int warm;
	/* Chebyshev semi-iteration of the Gauss–Seidel sweeps (Wang 2015): ρ ∈ [0, 1), an estimate of
	 * the sweeps' spectral radius; 0 (the default) turns it off. After sweep k > delay the
	 * positions (and with XPBD the multipliers) become ω_k (x̂_k − x_{k−2}) + x_{k−2}, x̂_k the
	 * sweep's result, with ω_{delay+1} = 2/(2 − ρ²) and ω_k = 4/(4 − ρ² ω_{k−1}) after it. A
	 * converged sweep's result is verified and returned as it is. The Jacobi variant refuses it. */
	float chebyshev_rho;
	int32_t chebyshev_delay; /* plain sweeps before the first extrapolation, ≥ 2 (default 10) */
	/* Stall rule of sere_pbd_project_stalling, s ∈ [0, 1). 0 (the default): the paper's stop,
	 * max |C/l| < λ_C or the cap. s > 0: also stop when a window of SERE_PBD_STALL_WINDOW sweeps
	 * lowered max |C/l| by less than the fraction s: once the shrunk layers disagree the hard
	 * constraints have no solution and the residual has a floor above λ_C. */
	float stall;
	/* A ground plane z ≥ ground (−INFINITY, the default: none). When a sweep's residual is below
	 * the tolerance, the particles below it are put onto it; if that moved one by more than
	 * ground_slack, the sweeps go on from the same multipliers (the step continues) until the
	 * ground holds too, within the cap; the residual is then confirmed on the grounded positions,
	 * the ones returned. At the cap the ground is put under the returned positions once more.
	 * sere_pbd_ground_push reports how far each particle was pushed. Gauss–Seidel only. */
	float ground;
	float ground_slack;
} sere_pbd_params;

/* Sweeps per stall check of sere_pbd_params.stall. */
#define SERE_PBD_STALL_WINDOW 10

/* k = 1, λ_C = 1e-3, 200 sweeps, no compliance, dt = 0.002 (Table 2), ω = 1.5, no stall rule. */
sere_pbd_params sere_pbd_params_default( void );

typedef struct sere_pbd_report
{
	int32_t iterations; /* sweeps run */
	float max_strain;	/* max |C/l| of the returned positions when converged, else of the last sweep */
	int hit_cap;		/* stopped by max_iterations, not by λ_C */
} sere_pbd_report;

/* How the constraints were scheduled, for reports and benchmarks. */
typedef struct sere_pbd_info
{
	int32_t colors;				   /* colors of the constraint graph (Sec. 5.2) */
	int32_t min_batch, max_batch;  /* smallest and largest color */
	int32_t bands;				   /* particle bands swept in parallel */
	int32_t interface_constraints; /* constraints joining two bands */
	int32_t lanes;				   /* SIMD lanes per sweep: constraints plus padding */
} sere_pbd_info;

typedef struct sere_pbd sere_pbd;

/* Builds the workspace for constraints (a[i], b[i]) over particles [0, particle_count):
 * colors them, orders the particles by breadth-first search, cuts that order into bands and
 * lays the constraints out in the order a sweep reads them. Everything a projection needs is
 * allocated here; projections allocate nothing. SERE_ERR_ARGUMENT for an index out of range or
 * a constraint joining a particle to itself, SERE_ERR_CAPACITY past SERE_MAX_COLORS. */
sere_status sere_pbd_create( const int32_t* a, const int32_t* b, int32_t constraint_count, int32_t particle_count,
							 sere_pbd** out );
void sere_pbd_destroy( sere_pbd* pbd );
const sere_coloring* sere_pbd_coloring( const sere_pbd* pbd );
sere_pbd_info sere_pbd_get_info( const sere_pbd* pbd );

/* Copies the rest lengths (indexed like the constraints given to create). SERE_ERR_GEOMETRY for
 * a length that is not positive and finite; the projections then refuse to run until a valid
 * set of lengths is given. */
sere_status sere_pbd_set_rest( sere_pbd* pbd, const float* rest );

/* Per-constraint compliance weights for XPBD: constraint j gets α_j = compliance · weight[j]
 * (indexed like the constraints given to create), so that classes of constraints can be
 * stiffer or softer than others (a vein stiffer than the blade) with one global scale. NULL
 * restores weight 1 everywhere (the default). SERE_ERR_ARGUMENT for a negative or non-finite
 * weight, which leaves the previous weights in place. */
sere_status sere_pbd_set_compliance_weights( sere_pbd* pbd, const float* weight );

/* The threads projection, sere_pbd_touch* and sere_pbd_set_rest run with (core/base.h: 0, the
 * initial count, is OpenMP's count at each call; SERE_ERR_ARGUMENT above SERE_MAX_THREADS). */
sere_status sere_pbd_set_threads( sere_pbd* pbd, int32_t threads );

/* v += g dt and p = x + v dt for particles [0, count) with inv_m > 0; pinned ones (inv_m = 0)
 * get v = 0 and keep p = x. On `threads` threads (core/base.h; above SERE_MAX_THREADS, that many). */
void sere_pbd_predict( int32_t count, const float* x, const float* y, const float* z, float* vx, float* vy, float* vz,
					   float* px, float* py, float* pz, const float* inv_m, const float gravity[3], float dt,
					   int32_t threads );

/* Projects the distance constraints C = |p_a − p_b| − l (Jeong Eq. 13) on the predicted positions,
 * Gauss–Seidel in sweeps, until max |C/l| < λ_C or the cap.
 *
 * Each constraint moves its ends along the constraint gradient by Δp_a = −w_a s ∇C,
 * Δp_b = +w_b s ∇C with s = k C/(w_a + w_b) (w = inverse mass; a constraint between two pinned
 * particles is skipped). With compliance α > 0 it is XPBD instead (Macklin et al. 2016): with
 * α̃ = α/dt² and a multiplier λ per constraint, reset at every call unless params->warm (one call = one step),
 * Δλ = (−C − α̃λ)/(w_a + w_b + α̃) and s = −Δλ (α̃ per constraint with
 * sere_pbd_set_compliance_weights); k is not used, and the residual tested against
 * λ_C is |C + α̃λ|/l, which is |C/l| when α = 0.
 *
 * Schedule: particles are kept inside the workspace as (x, y, z, w) records in breadth-first
 * order, cut into bands. A sweep projects the constraints inside each band (bands in parallel,
 * each one color after another, 16 constraints of one color per SIMD step), then those joining
 * bands r and r+1 for even r, then for odd r. The order depends on the constraints only, never
 * on the thread count, so 1 and 2 threads give bitwise the same positions. Bands hold equal
 * shares of the constraint ends; threads meet once per sweep (to decide whether to stop), and
 * within a sweep each band interface waits only for the bands and interfaces it shares
 * particles with.
 *
 * Stopping: a sweep records max |C/l| of each constraint just before projecting it; when that
 * is below λ_C a read-only pass measures the positions the sweep left and the call stops only
 * if they pass too, so a converged report is a property of the returned positions.
 *
 * Errors: SERE_ERR_NONFINITE for NaN or infinite positions or inverse masses (checked once on
 * entry) or a length that overflows during the sweeps; SERE_ERR_GEOMETRY for a constraint
 * whose ends coincide, or when no valid rest lengths were set; SERE_ERR_ARGUMENT for a
 * negative inverse mass or a parameter out of range. On any error px, py, pz are left exactly
 * as they were passed in. */
sere_status sere_pbd_project( sere_pbd* pbd, float* px, float* py, float* pz, const float* inv_m,
							  const sere_pbd_params* params, sere_pbd_report* report );

/* sere_pbd_project with the stall rule of params->stall (s > 0): every SERE_PBD_STALL_WINDOW
 * sweeps the call compares the residual of the window's last sweep with the previous window's,
 * and stops when it is above (1 − s) times that. The rule is checked inside the one call, so the
 * multipliers (XPBD), the Chebyshev sequence and the ground go on as they would without it: a
 * call that does not stall returns what sere_pbd_project returns, bit for bit. stalled is set
 * when the rule stopped it, neither converged nor at the cap (report->hit_cap is then 0). With
 * s = 0 or linear_stiffness this is sere_pbd_project. SERE_ERR_ARGUMENT as sere_pbd_project, and
 * for a NULL stalled or s outside [0, 1). */
sere_status sere_pbd_project_stalling( sere_pbd* pbd, float* px, float* py, float* pz, const float* inv_m,
									   const sere_pbd_params* params, sere_pbd_report* report, int* stalled );

/* The Jacobi variant, for comparison: every sweep measures all constraints on the same
 * positions, stores each one's correction, then every particle gathers the corrections of its
 * own constraints (in a fixed order, never scattered by threads) and moves by
 * ω/n_i Σ Δp_i (n_i its constraint count, ω = relaxation). Stops when the measured max |C/l|
 * (an exact property of the positions) is below λ_C. Same errors and options as
 * sere_pbd_project except linear_stiffness. Converges more slowly per sweep. */
sere_status sere_pbd_project_jacobi( sere_pbd* pbd, float* px, float* py, float* pz, const float* inv_m,
									 const sere_pbd_params* params, sere_pbd_report* report );

/* Adds to push[i] how far the ground (sere_pbd_params.ground) pushed particle i up during the
 * last projection, summed over its sweeps. */
sere_status sere_pbd_ground_push( const sere_pbd* pbd, float* push );

/* How far the last XPBD call's answer is from the step it solves. An XPBD step (Macklin et al.
 * 2016) is the pair (x, λ) with h = M (x − x̃) − ∇C(x)ᵀλ = 0 (their Eq. 8) and
 * g = C(x) + α̃λ = 0 (Eq. 9), x̃ the prediction the call started from. The sweeps drive g to the
 * tolerance and assume h stays 0, which holds while the gradients keep their directions; each
 * sweep moves the ends along the gradients of the moment, so once the multipliers are large and
 * the constraints turn during the step, h is what is left. Norms are over the particles that
 * count: inverse mass above 0 (a pinned particle takes any force) and not pushed by the ground
 * in the last call (the ground's reaction is no multiplier). */
typedef struct sere_pbd_residuals
{
	double primal;	   /* ‖h‖₂ */
	double inertia;	   /* ‖M (x − x̃)‖₂ */
	double constraint; /* ‖∇C(x)ᵀλ‖₂, the multipliers' forces */
	int32_t particles; /* particles counted */
} sere_pbd_residuals;

/* The residuals above for the positions px, py, pz a projection returned and the prediction tx, ty,
 * tz it was given, with the multipliers of that projection (indexed like the particles given to
 * create). Each particle sums its constraints in a fixed order, and the norms add fixed blocks of
 * particles in order, so the result has the same bits for any thread count. SERE_ERR_ARGUMENT for a
 * NULL argument or when the last projection to run was not an XPBD one that returned SERE_OK (then no
 * multipliers describe the positions; a call refused for its arguments runs nothing and changes
 * nothing). Allocates nothing: the block sums live in the workspace, so two calls on one workspace
 * must not run at once. */
sere_status sere_pbd_step_residual( const sere_pbd* pbd, const float* px, const float* py, const float* pz,
									const float* tx, const float* ty, const float* tz, const float* inv_m,
									sere_pbd_residuals* out );

/* The multipliers λ of the last XPBD projection, indexed like the constraints given to create
 * (lambda holds constraint_count floats). SERE_ERR_ARGUMENT as sere_pbd_step_residual. */
sere_status sere_pbd_multipliers( const sere_pbd* pbd, float* lambda );

/* One sweep of sere_pbd_project's schedule, with the same loads and stores of both constraint
 * ends, but the arithmetic replaced by a copy: the memory floor of a sweep, for benchmarks.
 * Leaves the positions bitwise unchanged. */
sere_status sere_pbd_touch( sere_pbd* pbd, float* px, float* py, float* pz, const float* inv_m );

/* sere_pbd_touch with `sweeps` sweeps in one call: the floor of a sere_pbd_project call that
 * runs that many sweeps (the same entry check, packing, parallel region, barriers and per-sweep
 * exchange, unpacking). SERE_ERR_ARGUMENT for sweeps < 1. */
sere_status sere_pbd_touch_sweeps( sere_pbd* pbd, float* px, float* py, float* pz, const float* inv_m, int32_t sweeps );

/* The floor of an XPBD call (compliance > 0): sere_pbd_touch_sweeps plus what an XPBD sweep moves
 * beyond a PBD one, each constraint's compliance weight loaded and its multiplier loaded and
 * stored (the multipliers are zeroed at the call's start, as an XPBD call without `warm` does). */
sere_status sere_pbd_touch_sweeps_xpbd( sere_pbd* pbd, float* px, float* py, float* pz, const float* inv_m,
										int32_t sweeps );

/* v = (p − x)/dt and x = p for particles [0, count) (Sec. 5.2: Δv = Δx/Δt), on `threads`
 * threads as sere_pbd_predict. */
void sere_pbd_finish( int32_t count, float* x, float* y, float* z, float* vx, float* vy, float* vz, const float* px,
					  const float* py, const float* pz, float dt, int32_t threads );

#ifdef __cplusplus
}
#endif
