/* sere — osmotic water flow on one layer (Sec. 4, Jeong Eq. 3–10), solved as an SPD system with the
 * CG of cg.h, preconditioned by Jacobi, multicolor SGS or aggregation multigrid, by stiffness. */
#pragma once

#include "solve/cg.h"

#ifdef __cplusplus
extern "C"
{
#endif

typedef enum sere_osmosis_mode
{
	/* Jeong Eq. 8–9 as written: each row weighted by the paper's 2/E_i. Made symmetric by w = M c and
	 * a row scale of E_i/2 (docs/DESIGN.md): (E_i M_i/2) c_i + Δt Σ_j K_ij (c_i − c_j) = (E_i/2) rhs_i. */
	SERE_OSMOSIS_PAPER = 0,
	/* The symmetric weight 4/(E_i + E_j) instead of 2/E_i: M_i c_i + Δt Σ_j 4/(E_i+E_j) K_ij (c_i − c_j)
	 * = rhs_i. Summing the rows, Σ M_i c_i = Σ w_i = Σ rhs_i: flow moves water without creating
	 * or destroying it. */
	SERE_OSMOSIS_CONSERVATIVE = 1,
} sere_osmosis_mode;

typedef struct sere_osmosis_params
{
	double dt;
	double lambda_min, lambda_max; /* λ_ij = λ_min(1 − τ̄) + λ_max τ̄, τ̄ = (τ_i + τ_j)/2 (Sec. 4) */
	double water_rate;			   /* signed: Table 2's w_loss, −0.1 = every particle loses 0.1 per unit time */
	sere_osmosis_mode mode;
	double tolerance;		/* CG relative residual */
	int32_t max_iterations; /* CG cap */
	const int32_t* supply;	/* particles (global indices) with a fixed water supply (Fig. 9), or NULL */
	int32_t supply_count;
	double supply_rate; /* water added per unit time at each supply particle */
} sere_osmosis_params;

sere_osmosis_params sere_osmosis_params_default( void );

/* The preconditioner, chosen per step from q = max_i Σ_{j≠i} |a_ij| / a_ii of the assembled
 * system. Gershgorin bounds the Jacobi-scaled spectrum by [1 − q, 1 + q], so Jacobi PCG's
 * condition number is at most (1 + q)/(1 − q), and its iterations grow like its square root:
 * below the threshold (κ ≤ 39) the system is easy, Jacobi needs a few iterations a frame from
 * the extrapolated start (maple, λ = 0.04: q = 0.73 on T, 0.84 on V, about 3 iterations a frame),
 * and SGS's fixed cost per solve (two sweeps into and out of its variables, a residual check)
 * would outweigh what it saves. Above it the system is diffusion-dominated (plane tree,
 * λ = 100: q = 0.9999 on V, about 90 Jacobi iterations a frame), SGS halves the iterations at
 * about 1.3× the cost of one (BM_PCG). */
#define SERE_OSMOSIS_SGS_ABOVE 0.95

/* Above this q (Jacobi's κ bound 400) the system is nearly singular on its smooth vectors and
 * the aggregation multigrid takes over (sere_cg_solve_amg). A V-cycle costs about three SGS-PCG
 * iterations, so it pays where it saves more than two of every three: on the 30 × 20 test layer's
 * first step SGS needs 38 iterations at q = 0.990, 64 at 0.9966 and 89 at 0.9990, the multigrid
 * 18 at 0.9995; on the plane tree's V layer (q = 0.9999) at frame 100, 148 against 13. Its
 * levels are built at the first such step. */
#define SERE_OSMOSIS_AMG_ABOVE 0.995

/* The multigrid's coarse levels follow the matrix every this many of its steps (sere_amg_update)
 * and lag it in between; its finest level always has the step's values. A drying layer's matrix
 * drifts by about 10⁻³ a step: on the plane tree (200 frames of table1) the V iterations stay at
 * 6.7 a frame whether the coarse levels follow every step, every 16th or only the first, and
 * following every 16th instead of every step saves 0.08 ms a frame at 1 thread. */
#define SERE_OSMOSIS_AMG_REFRESH 16

typedef enum sere_osmosis_precond
{
	SERE_OSMOSIS_JACOBI,
	SERE_OSMOSIS_SGS,
	SERE_OSMOSIS_AMG,
} sere_osmosis_precond;

typedef struct sere_osmosis_report
{
	int32_t iterations;
	double residual;
	sere_osmosis_precond preconditioner; /* the step's, by q */
	double offdiag;						 /* q of the assembled system (above) */
	double water_before, water_after;
	int stopped; /* the layer had no water left: nothing was solved (Sec. 6) */
} sere_osmosis_report;

typedef struct sere_osmosis sere_osmosis;

/* A layer is the particles [first, first + count) and the springs joining them (indices are
 * global, as in sere_springs). The CSR pattern (diagonal plus one entry per spring end) is
 * built here once; each step only refills values. SERE_ERR_ARGUMENT for a spring end outside
 * the layer or a spring joining a particle to itself, and for counts whose CSR (count +
 * 2 · spring_count entries) or last index would not fit an int32_t. */
sere_status sere_osmosis_create( int32_t first, int32_t count, const int32_t* a, const int32_t* b, int32_t spring_count,
								 sere_osmosis** out );
void sere_osmosis_destroy( sere_osmosis* osmosis );

/* The threads sere_osmosis_step runs with, its assembly and its CG solve (core/base.h: 0, the
 * initial count, is OpenMP's count at each step; SERE_ERR_ARGUMENT above SERE_MAX_THREADS). */
sere_status sere_osmosis_set_threads( sere_osmosis* osmosis, int32_t threads );

/* One implicit step: assemble, solve for c, w = max(0, M c), m = M + w (Jeong Eq. 10). Arrays are
 * global particle arrays; only the layer's entries are read or written. M must be positive.
 * CG starts from the concentration w/M extrapolated from the previous steps: the parabola
 * 3 c_n − 3 c_{n−1} + c_{n−2} once there are three, the line 2 c_n − c_{n−1} at the second
 * step, c_n at the first, and never below 0. A drying layer's concentration moves smoothly, so
 * this guess is far closer than c_n alone (plane tree, λ = 100: 556 iterations per step in the
 * first frames, 18875 over 200 frames against 29738 with the line alone).
 *
 * SERE_ERR_ARGUMENT for a NULL argument, dt not positive, a λ negative or NaN, a supply index
 * outside the layer, an M not positive or not finite, or a w not finite; SERE_ERR_NONFINITE for
 * a τ not finite; SERE_ERR_GEOMETRY for a spring of zero or non-finite length; otherwise the CG
 * solve's status (cg.h). w and m are left as they were on any status but SERE_OK and
 * SERE_ERR_NO_CONVERGE. */
sere_status sere_osmosis_step( sere_osmosis* osmosis, const float* x, const float* y, const float* z, const float* tau,
							   const double* M, double* w, double* m, const sere_osmosis_params* params,
							   sere_osmosis_report* report );

/* The assembled system of the last step (for --dump and tests): A, right-hand side b and
 * solution c, all in the layer's local numbering. A step writes A's values only into its
 * preconditioner's layout; sere_osmosis_matrix copies them into the CSR arrays the first time it
 * is called after a step (hence the pointer is not const), and the CSR stays valid until the
 * next step. */
const sere_csr* sere_osmosis_matrix( sere_osmosis* osmosis );
const double* sere_osmosis_rhs( const sere_osmosis* osmosis );
const double* sere_osmosis_solution( const sere_osmosis* osmosis );

#ifdef __cplusplus
}
#endif
