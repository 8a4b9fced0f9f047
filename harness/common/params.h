/* sere harness — every simulation parameter by name: defaults, Table 2 presets, --set overrides. */
#pragma once

#include "drying/layers.h"

#include <stddef.h>
#include <stdio.h>

#ifdef __cplusplus
extern "C"
{
#endif

typedef struct sere_sim_params
{
	sere_layer_params layer; /* h_vein, h_surf, omega_*, D, m_min, m_max, mu0 */
	double dt;
	double gravity[3];
	double damping; /* fraction of every velocity removed per frame */
	double ground;	/* height of the supporting plane below the leaf (z), or -inf for none */
	double lambda_min, lambda_max;
	double water_rate_t; /* signed water rate of the T layer: Table 2's w_loss^T, −0.1 = losing 0.1 per unit time */
	double water_rate_v; /* the same for the V layer */
	double sigma_vein, sigma_surf;
	double alpha;			   /* exponent of Jeong Eq. 12 (Sec. 5.1: ≈ 1.3) */
	double min_length_ratio;   /* springs stop shrinking below this fraction of l⁰ */
	double stiffness;		   /* PBD k ∈ [0, 1] */
	double strain_tolerance;   /* the stop: max |C + α̃λ|/l (XPBD) or max |C/l| < λ_C (the paper, compliance 0) */
	double compliance;		   /* XPBD compliance α of the blade's springs; 0 = the paper's hard PBD */
	double vein_compliance;	   /* compliance weight of vein springs (α_vein = α · this) */
	double voronoi_compliance; /* compliance weight of the Voronoi layer's other springs */
	double link_compliance;	   /* compliance weight of the L springs */
	double friction_static;	   /* Coulomb coefficients of the ground contact */
	double friction_kinetic;
	double max_iterations;		/* PBD iteration cap */
	double chebyshev_rho;		/* Chebyshev semi-iteration of the XPBD sweeps (Wang 2015): 0 off, else ρ */
	double pbd_stall;			/* 0: the paper's stop rule; s > 0: also stop when 10 sweeps gain less than s */
	double collision_thickness; /* vertex–triangle proximity distance, leaf units (at rest when scaled) */
	double collision_scaling;	/* the thickness shrinks with the triangle layer (1) or stays fixed (0) */
	double restore_measured;	/* Jeong Eq. 14 with ĥ measured before collisions (1) or the rest h (0) */
	double conservative;		/* osmosis: 0 = the paper's Jeong Eq. 8, 1 = conservative weights */
	double soften;				/* Sec. 7: stiffness scaled by relative water content (1) or constant (0) */
	double crease;				/* Sec. 3.1 initial shaping: Voronoi vein springs shortened by this fraction */
	double curl;				/* ... and the other Voronoi springs lengthened by this fraction */
	double local_stop;			/* Sec. 6 stop where a layer runs dry (1) or only for the whole leaf (0) */
	double face_down;			/* the leaf lies on the face its Voronoi layer is offset to (+n): mirrored through z */
	double seed;
} sere_sim_params;

sere_sim_params sere_sim_params_default( void );

/* Sets one "key=value"; 0 on success, else -1 with a one-line message in err naming the key. */
int sere_params_set( sere_sim_params* params, const char* assignment, char* err, size_t err_size );

/* Loads a preset by name (data/presets/NAME.preset, searched in SERE_DATA, ./data and the
 * install prefix) or by path; 0 on success, else -1 with a one-line message. */
int sere_params_load_preset( sere_sim_params* params, const char* name_or_path, char* err, size_t err_size );

/* A preset (may be NULL) then each "key=value" in order, the way every command applies its
 * --preset and --set options; 0 on success, else -1 with a one-line message. */
int sere_params_apply( sere_sim_params* params, const char* preset, const char* const* sets, int set_count, char* err,
					   size_t err_size );

/* Writes every key = value, one per line, for summaries and --help. */
void sere_params_print_json( const sere_sim_params* params, FILE* f, const char* indent );
/* Every key with its description, default and range, for --help. */
void sere_params_describe( FILE* f );

/* Finds a data file (relative to SERE_DATA, ./data, or SERE_DATA_DIR compiled in); writes the
 * full path and returns 0, or -1 when it does not exist. */
int sere_data_path( const char* relative, char* path, size_t path_size );

#ifdef __cplusplus
}
#endif
