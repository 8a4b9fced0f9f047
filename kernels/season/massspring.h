/* sere — the improved mass-spring model of seed 002 (Tang, Wu, Fan 2013, Sec. 4): the leaf's
 * triangle mesh as particles and springs, particle masses from a grayscale mask map (Tang Eq. 3),
 * explicit Euler (Tang Eq. 1) and velocity-based strain limiting (Tang Eq. 2) so that no spring strays
 * more than τ_c from its natural length.
 *
 * Springs. The structural springs are the mesh edges, each once (Sec. 4.2, steps 1–3). A mesh
 * of edges alone has no resistance to bending, so a leaf held at its petiole would hang like a
 * cloth; every interior edge therefore also gets a flexion spring joining the two vertices
 * opposite it (the usual cloth bending spring).
 *
 * Forces (the seed leaves them to the user; these are ours):
 *   gravity       m g on every particle;
 *   springs       f = (k ε + c (v_b − v_a)·n) n on a, −f on b, with n the unit vector a→b,
 *                 ε = (|x_b − x_a| − L)/L the strain and c a damping coefficient along the spring;
 *   drying        the structural natural lengths contract, L = (1 − shrink) L⁰: the blade
 *                 shrinks as it loses water (Sec. 4: "different amounts of contraction during
 *                 the dehydration process");
 *   curling       the flexion natural lengths contract more, L = (1 − curl) L⁰: the upper
 *                 surface shrinking more than the lower one folds the blade across every
 *                 edge. A flat blade is an unstable equilibrium of that fold, so the caller
 *                 gives the rest shape a slight cup (real leaves are never flat), which picks
 *                 the side the leaf curls to;
 *   drag          every velocity loses the fraction `drag` per step. Drag proportional to
 *                 momentum makes a particle's drift speed ∝ F/m, so under the same forces the
 *                 light (dark-masked) regions deform first and most, as Sec. 4.2 describes.
 *
 * One step (Tang Eq. 1, explicit Euler): a = g + F_springs/m; v ← (1 − drag)(v + a Δt); the
 * velocities are then limited (Tang Eq. 2); x ← x + v Δt. Pinned particles (inverse mass 0) keep
 * v = 0.
 *
 * Strain limiting (Tang Eq. 2, after Provot's deformation constraints applied to velocities): for a
 * structural spring (a, b) the relative position after the step is p = x_ab + v_ab Δt. When |p|
 * lies outside [(1 − τ_c) L, (1 + τ_c) L] the relative velocity along p is changed so that |p|
 * lands on the band; the change is shared by inverse mass. Springs inside the band keep their
 * velocities. Sweeps over all structural springs (Gauss–Seidel; in parallel by particle bands
 * and, inside a band or a cut between bands, by graph coloring, see sere_massspring_get_topology and
 * color.h) aim at the band narrowed by the tolerance δ on both sides and repeat until a
 * sweep finds no spring more than δ L off that inner band and a measurement confirms every
 * spring inside the true band, so a converged step keeps every structural spring within τ_c of
 * its natural length (up to float rounding of the positions, ~1e-6 relative). Gauss–Seidel
 * needs many sweeps when long chains of springs sit at the limit (a sheet hanging from one
 * corner: ~140 sweeps at δ = 1e-3); a smaller δ costs more sweeps, not accuracy of the limit.
 * color.h). */
#pragma once

#include "core/base.h"

#ifdef __cplusplus
extern "C"
{
#endif

/* Particle state in SoA; every array holds at least count entries. */
typedef struct sere_massspring_particles
{
	int32_t count;
	float *x, *y, *z;
	float *vx, *vy, *vz;
	const float* inv_m; /* 1/m, 0 pins a particle */
} sere_massspring_particles;

typedef struct sere_massspring_params
{
	float dt;
	float gravity[3];
	float stiffness;		/* k of the structural springs (force per unit strain) */
	float bend_stiffness;	/* k of the flexion springs */
	float damping;			/* c: force per unit relative speed along a spring */
	float drag;				/* fraction of every velocity removed per step, in [0, 1) */
	float shrink;			/* structural contraction, L = (1 − shrink) L⁰, in [0, 1) */
	float curl;				/* flexion contraction, L = (1 − curl) L⁰, in [0, 1) */
	float strain_limit;		/* τ_c of Tang Eq. 2, in (0, 1) */
	float strain_tolerance; /* δ, in (0, τ_c): the margin the sweeps aim inside the band by */
	int32_t max_sweeps;		/* cap on strain-limiting sweeps per step, ≥ 1 */
} sere_massspring_params;

/* dt 1e-3, gravity (0, 0, −1), stiffness 40, bend_stiffness 4, damping 0.02, drag 0.01,
 * shrink 0, curl 0, τ_c 0.1 (the seed's value), δ 1e-3, 500 sweeps. Units: the leaf is
 * about 1 long and masses lie in [0.1, 1]. */
sere_massspring_params sere_massspring_params_default( void );

/* Tang Eq. 3: the seed maps a mask pixel's gray value to a particle mass through its logarithm,
 * "which makes the change of the masses more gentle and smooth compared with the changes of
 * grayscale values". Ours, for gray g ∈ [0, 1] (G = 255 g on the 8-bit scale):
 *     m = m_min + (m_max − m_min) ln(1 + 255 g) / ln 256,
 * so black gives m_min, white m_max, and the mass rises steeply over the darkest grays and
 * gently over the rest. g outside [0, 1] is clamped. Writes n masses; SERE_ERR_NONFINITE for a
 * NaN gray, SERE_ERR_ARGUMENT unless 0 < m_min ≤ m_max (finite). */
sere_status sere_massspring_mass_from_gray( const float* gray, int32_t n, float m_min, float m_max, float* mass );

typedef struct sere_massspring sere_massspring;

/* Builds the springs of a triangle mesh whose current positions are the rest shape: natural
 * lengths L⁰ are the distances there. Everything a step needs is allocated here.
 * SERE_ERR_ARGUMENT for a vertex index out of range, a triangle repeating a vertex or more
 * than INT32_MAX / 3 triangles,
 * SERE_ERR_GEOMETRY for an edge shared by more than two triangles or of zero length,
 * SERE_ERR_NONFINITE for a NaN or infinite coordinate, SERE_ERR_CAPACITY past SERE_MAX_COLORS. */
sere_status sere_massspring_create( const float* x, const float* y, const float* z, int32_t vertex_count,
									const int32_t* tri, int32_t triangle_count, sere_massspring** out );
void sere_massspring_destroy( sere_massspring* ms );

/* The threads sere_massspring_step runs with (core/base.h: 0, the initial count, is OpenMP's
 * count at each step; SERE_ERR_ARGUMENT above SERE_MAX_THREADS). */
sere_status sere_massspring_set_threads( sere_massspring* ms, int32_t threads );

/* The springs as stored: structural springs in the order a sweep limits them, then the
 * flexion springs. a[k] < b[k]. The structural springs come in runs [run_offsets[k],
 * run_offsets[k + 1]) of one color within one band or one cut between neighbouring bands (the
 * particles cut by breadth-first level into band_count bands); no two springs of a run share a
 * particle. Limiting the runs one after another in index order is what a sweep does, so a
 * serial twin reproduces it. */
typedef struct sere_massspring_topology
{
	int32_t vertex_count;
	int32_t structural_count;
	int32_t flexion_count;
	const int32_t* a; /* structural_count + flexion_count entries */
	const int32_t* b;
	const float* rest0;			/* natural length L⁰ */
	int32_t color_count;		/* colors of the structural springs */
	int32_t band_count;			/* particle bands */
	int32_t run_count;			/* (2 band_count − 1) color_count runs, some empty */
	const int32_t* run_offsets; /* run_count + 1 entries */
} sere_massspring_topology;

sere_massspring_topology sere_massspring_get_topology( const sere_massspring* ms );

typedef struct sere_massspring_report
{
	int32_t sweeps;	  /* strain-limiting sweeps run */
	int32_t limited;  /* structural springs the first sweep corrected */
	float max_strain; /* max | |x_b − x_a| / L − 1 | over structural springs after the step */
	int hit_cap;	  /* the sweeps stopped at max_sweeps, not at the tolerance */
} sere_massspring_report;

/* Advances the particles by one step of params->dt. SERE_ERR_ARGUMENT for a particle count other
 * than the mesh's, a parameter out of range or a negative inverse mass; SERE_ERR_NONFINITE for a
 * NaN or infinite position, velocity or inverse mass on entry (nothing is changed then);
 * SERE_ERR_NO_CONVERGE when the sweeps hit the cap: the step is still taken and the report says
 * how far off the band the springs are. report may be NULL. */
sere_status sere_massspring_step( sere_massspring* ms, sere_massspring_particles* particles,
								  const sere_massspring_params* params, sere_massspring_report* report );

/* The floor of sere_massspring_step: the memory a step with `sweeps` strain-limiting sweeps moves,
 * with sums in place of its arithmetic. It packs the records, loads every spring's two ends and
 * natural length and stores a force per spring, gathers each particle's forces and writes its
 * velocity record, runs `sweeps` sweeps that load every structural spring's ends and length
 * (meeting at the same barriers as a step's), one confirming pass of the same loads, and writes
 * the particles back. It leaves out the stores of the springs a sweep corrects (a step stores
 * only the SIMD chunks with a spring off the band, a few percent after the first sweep) and
 * every square root and division; the integration runs as a step's with Δt = 0, a few
 * multiply-adds a particle. Positions are left as they were, and so are velocities except those of
 * pinned particles, which become 0 as in a step. SERE_ERR_ARGUMENT for a particle count other
 * than the mesh's, a NULL array or sweeps < 1; SERE_ERR_NONFINITE as sere_massspring_step. */
sere_status sere_massspring_touch( sere_massspring* ms, sere_massspring_particles* particles, int32_t sweeps );

#ifdef __cplusplus
}
#endif
