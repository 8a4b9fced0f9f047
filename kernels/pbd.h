/* sere — position-based dynamics of distance constraints (Sec. 5.2, Eq. 13), Gauss–Seidel in
 * parallel by graph coloring. Works on plain index / rest-length / position arrays. */
#pragma once

#include "color.h"

#ifdef __cplusplus
extern "C"
{
#endif

typedef struct sere_pbd_params
{
	float stiffness;		/* k ∈ [0, 1]: the fraction of each correction applied (Sec. 5.2) */
	float tolerance;		/* λ_C: stop when max |C/l| < λ_C over a sweep */
	int32_t max_iterations; /* sweep cap */
	float compliance;		/* XPBD compliance α (0: the paper's PBD); needs dt */
	float dt;
} sere_pbd_params;

sere_pbd_params sere_pbd_params_default( void );

typedef struct sere_pbd_report
{
	int32_t iterations;
	float max_strain; /* max |C/l| of the final positions when converged, else of the last sweep */
	int hit_cap;	  /* stopped by max_iterations, not by λ_C */
} sere_pbd_report;

typedef struct sere_pbd sere_pbd;

/* Colors the constraints, stores them in color order and builds the particle → constraint
 * adjacency for the Jacobi variant. */
sere_status sere_pbd_create( const int32_t* a, const int32_t* b, int32_t constraint_count, int32_t particle_count,
							 sere_pbd** out );
void sere_pbd_destroy( sere_pbd* pbd );
const sere_coloring* sere_pbd_coloring( const sere_pbd* pbd );

/* Copies the rest lengths (in the caller's constraint order) into color order;
 * SERE_ERR_GEOMETRY for a non-positive or non-finite length. */
sere_status sere_pbd_set_rest( sere_pbd* pbd, const float* rest );

/* v += g dt and p = x + v dt for particles [0, count) with inv_m > 0; pinned ones keep p = x. */
void sere_pbd_predict( int32_t count, const float* x, const float* y, const float* z, float* vx, float* vy, float* vz,
					   float* px, float* py, float* pz, const float* inv_m, const float gravity[3], float dt );

/* Projects every constraint color by color, OpenMP across each batch and SIMD across its
 * constraints, until max |C/l| < λ_C or the cap. SERE_ERR_GEOMETRY when a constraint has zero
 * length, SERE_ERR_NONFINITE when a position is NaN or infinite. */
sere_status sere_pbd_project( sere_pbd* pbd, float* px, float* py, float* pz, const float* inv_m,
							  const sere_pbd_params* params, sere_pbd_report* report );

/* The Jacobi variant: every particle gathers the corrections of its constraints from the same
 * state and moves by their mean (for comparison; converges more slowly). */
sere_status sere_pbd_project_jacobi( sere_pbd* pbd, float* px, float* py, float* pz, const float* inv_m,
									 const sere_pbd_params* params, sere_pbd_report* report );

/* v = (p − x)/dt and x = p for particles [0, count) (Sec. 5.2: Δv = Δx/Δt). */
void sere_pbd_finish( int32_t count, float* x, float* y, float* z, float* vx, float* vy, float* vz, const float* px,
					  const float* py, const float* pz, float dt );

#ifdef __cplusplus
}
#endif
