/* sere — one frame of Algorithm 1 on a whole leaf, composed from the kernels: osmotic flow on
 * both layers (Jeong Eq. 9) → masses (Jeong Eq. 10) → rest lengths (Jeong Eq. 12) → gravity and integration →
 * ĥ → projection of the T, V and L constraints (Jeong Eq. 13) → self-collision of the triangle layer
 * → Voronoi restore (Jeong Eq. 14). Another program can drive a leaf through this API alone. */
#pragma once

#include "drying/layers.h"
#include "drying/osmosis.h"
#include "drying/shrink.h"
#include "mesh/measure.h"
#include "solve/collide.h"
#include "solve/pbd.h"
#include "solve/vbd.h"

#ifdef __cplusplus
extern "C"
{
#endif

typedef struct sere_leaf_params
{
	float dt;
	float gravity[3];
	float ground;		 /* z of a supporting plane below the leaf; -INFINITY for none */
	float damping;		 /* fraction of every velocity removed per frame (the damping step of Müller et al. 2007) */
	double water_rate_t; /* signed (Table 2 w_loss^T): negative loses water */
	double water_rate_v; /* signed (Table 2 w_loss^V) */
	sere_osmosis_params osmosis; /* λ, mode and CG settings; its water_rate and dt are set per layer */
	sere_shrink_params shrink;
	/* pbd.compliance > 0 (the default): every frame is one XPBD step (Macklin et al. 2016), the
	 * minimum of inertia + elastic energy with compliance α per spring, which exists even when
	 * the shrunk layers admit no shape meeting every rest length; the frame stops when the
	 * residual max |C + α̃λ|/l is below pbd.tolerance. pbd.compliance = 0: the paper's PBD, which
	 * stops at max |C/l| < λ_C or the cap (Sec. 5.2, for comparing with Table 1). */
	sere_pbd_params pbd;
	float vein_compliance;	  /* compliance weight of vein springs, T and V (α_vein = α · this): veins are stiffer */
	float voronoi_compliance; /* compliance weight of the Voronoi layer's other springs */
	float link_compliance;	  /* compliance weight of the L springs (thickness) */
	float friction_static, friction_kinetic; /* Coulomb coefficients of the ground contact */
	sere_collide_params collide;
	int collisions; /* run the self-collision pass (when collide.thickness > 0) */
	/* 1: collide.thickness is the thickness at rest and shrinks with the triangle layer, times
	 * sere_leaf_thickness_scale every frame, as the leaf's own thickness shrinks with its
	 * springs (Sec. 5.1). 0: the thickness stays fixed. */
	int scale_thickness;
	int restore_measured; /* Jeong Eq. 14 with ĥ measured before collisions (1) or the rest h (0) */
	int soften;			  /* Sec. 7: stiffness scaled by relative water content */
	/* 1: Sec. 6's stop applied where a layer runs dry (a particle whose neighbour in the other
	 * layer has run dry keeps its water and mass); 0: only for the whole leaf, when a whole layer
	 * has run dry. */
	int local_stop;
	/* 1 (the default): each frame measures how far its XPBD step is from the step's first
	 * condition (sere_pbd_step_residual, into sere_leaf_stats.step_primal), outside the timed
	 * parts: a copy of the prediction and a pass over every particle's springs. */
	int step_residual;
	/* 1 (the default): each frame's step is the descent of the XPBD step's energy (solve/vbd.h: a
	 * Newton step per particle, the same compliances and weights), until a sweep moves no particle
	 * farther than descent_tolerance times the mean T spring (scaled with the layer), within
	 * pbd.max_iterations, with Chebyshev semi-iteration (descent_rho, descent_delay) and the ground
	 * as a bound: a rest state of the step, where XPBD stops once the constraints are met and
	 * leaves the force balance (docs/DESIGN.md §8). Needs pbd.compliance > 0 and every compliance
	 * weight > 0. 0: XPBD (pbd's own Chebyshev settings). */
	int descent;
	/* The descent's stop, a fraction of the mean T spring (default 1e-6). The sweeps contract
	 * slowly on a dried leaf, so a sweep's move understates the distance left by the factor
	 * 1/(1 − ρ): stopped at 1e-5, the green maple at 300 points ends 0.19 spacings from its
	 * converged shape. The default lies below the rounding of the coordinates at the presets'
	 * sizes (3e-6 of a spring at 800 points), so the stop is that rounding
	 * (sere_vbd_report.tolerance): each frame is as converged as single precision allows. */
	float descent_tolerance;
	/* The descent's Chebyshev semi-iteration (sere_vbd_params): ρ 0.8 after 2 plain sweeps (the
	 * default; from a cold start ρ 0.9 did better, from the warm start below 0.8: on the Table 1
	 * leaves 7.5 / 13.2 / 2.5 sweeps a frame where 0.9 took 9.2 / 16.2 / 2.5). */
	float descent_rho;
	int32_t descent_delay;
	/* 1 (the default): each frame's sweeps begin at the prediction plus the last frame's
	 * correction (sere_vbd_params.warm_start). A leaf at rest or drying slowly needs nearly the
	 * same correction every frame (the gravity drop its springs hold back, the shrinkage the
	 * damped velocity lags), so the sweeps begin near the answer. With the Chebyshev default the
	 * presets at 800 points take 0.12–0.42 of the plain sweeps from the prediction and end within
	 * 0.07 spacings of their shape, but for the grass, whose nearly unstressed blade's shape is set
	 * at the rounding of its coordinates (docs/DESIGN.md §8). 0: at the prediction. */
	int descent_warm;
} sere_leaf_params;

sere_leaf_params sere_leaf_params_default( void );

typedef struct sere_leaf_stats
{
	double water_t, water_v; /* total water per layer after the frame */
	double relative_water;	 /* total water / initial total water */
	int32_t cg_iterations_t, cg_iterations_v;
	int32_t pbd_iterations;
	float max_strain; /* max |C/l| after projection */
	/* the stop measure after projection: max |C + α̃λ|/l (XPBD), max |C/l| (paper), the last sweep's
	 * largest move over the mean T spring (descent) */
	float residual;
	/* ‖h‖/‖∇Cᵀλ‖ of the XPBD step (Macklin et al. 2016 Eq. 8, sere_pbd_step_residual): the share of
	 * the multipliers' forces the step leaves unbalanced (descent: ‖∂E/∂x‖ over the springs' forces,
	 * sere_vbd_step_residual); NaN when not measured (step_residual 0, the paper's PBD) */
	float step_primal;
	int pbd_converged; /* the residual reached pbd.tolerance (and the ground was met) before the cap */
	int32_t grounded;  /* particles (either layer) touching the ground after the frame */
	int pbd_hit_cap;
	int pbd_stalled;		   /* stopped by the stall rule (pbd.stall), neither converged nor at the cap */
	int32_t contacts;		   /* vertex–triangle contacts found */
	int32_t edge_contacts;	   /* edge–edge contacts found */
	int32_t unresolved;		   /* contacts of either kind still short of the thickness after the pass */
	float collision_thickness; /* the thickness the pass used */
	int desiccated;			   /* a layer ran dry: flow and shrinkage have stopped (Sec. 6) */
	/* Table 1's breakdown, milliseconds of wall time; the measures beside the frame (max_strain,
	 * step_primal) are not in it */
	double osmosis_ms, dynamics_ms, collisions_ms, total_ms;
} sere_leaf_stats;

typedef struct sere_leaf_sim sere_leaf_sim;

/* The simulation keeps a pointer to model and changes it in place every frame. */
sere_status sere_leaf_create( sere_model* model, sere_leaf_sim** out );
void sere_leaf_destroy( sere_leaf_sim* sim );

/* The threads every kernel of a step runs with: osmosis, shrinkage, projection, collisions and
 * the leaf's own loops (core/base.h: 0, the initial count, is OpenMP's count at each step; the
 * osmosis and shrinkage, and the descent's sweeps, run on one thread while that has been measured
 * the faster). SERE_ERR_ARGUMENT above SERE_MAX_THREADS, SERE_ERR_MEMORY (nothing changed) when the collision
 * workspace cannot make buffers for that many. */
sere_status sere_leaf_set_threads( sere_leaf_sim* sim, int32_t threads );

/* One frame of Algorithm 1. SERE_ERR_ARGUMENT for a NULL argument, dt not positive, a negative
 * compliance or friction, damping outside [0, 1], or a ground that is NaN or +∞; otherwise the
 * first failing kernel's status. */
sere_status sere_leaf_step( sere_leaf_sim* sim, const sere_leaf_params* params, sere_leaf_stats* stats );

/* Initial shaping (Sec. 3.1, Fig. 3g): vein springs of the Voronoi layer shortened by crease
 * and the other Voronoi springs lengthened by curl (fractions of l⁰), projected to rest, and the
 * result taken as the new rest state (l⁰ and positions). SERE_ERR_ARGUMENT, with nothing
 * changed, for a NULL argument, crease ≥ 1 or curl ≤ −1 (a rest length not positive) or NaN. */
sere_status sere_leaf_shape_initial( sere_leaf_sim* sim, float crease, float curl, const sere_pbd_params* pbd );

/* Σ l / Σ l⁰ over the model's T springs: how far the triangle layer has shrunk (1 at rest). A
 * fixed collision thickness outgrows a shrinking sheet: once its edges are not much longer than
 * the thickness, vertices touch the triangles a few rings away in their own sheet. Summed in
 * spring order, so the same bits for every thread count. */
float sere_leaf_thickness_scale( const sere_model* model );

/* The triangle layer of model as the input of sere_shape_measure (kernels/mesh/measure.h): current
 * positions, plane coordinates u, v, triangles, the T springs as edges with their vein bit, the
 * outline flags, and the ground (-INFINITY for none). */
sere_shape_input sere_leaf_shape_input( const sere_model* model, double ground );

/* Per-particle relative water content w / w⁰ (0 where w⁰ = 0), for colors and outputs. */
void sere_leaf_relative_water( const sere_leaf_sim* sim, float* out );

#ifdef __cplusplus
}
#endif
