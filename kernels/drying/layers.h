/* sere — the triangle–Voronoi double layer (Sec. 3.2) as structure-of-arrays particles and
 * springs, with distances, τ and masses from the base (Sec. 3.3, Jeong Eq. 1–2). */
#pragma once

#include "core/base.h"

#ifdef __cplusplus
extern "C"
{
#endif

/* Particles: the N triangle-layer particles come first, then one Voronoi particle per triangle.
 * Every array holds capacity = sere_pad(count) entries; the padding is zero. */
typedef struct sere_particles
{
	int32_t count;
	int32_t capacity;
	float *x, *y, *z;	 /* position */
	float *vx, *vy, *vz; /* velocity */
	float *px, *py, *pz; /* predicted position (PBD) */
	float* inv_m;		 /* inverse mass used by the dynamics; 0 pins a particle */
	double* w;			 /* water */
	double* M;			 /* solute */
	double* m;			 /* total mass m = M + w (Jeong Eq. 10) */
	double* m0;			 /* initial mass (Jeong Eq. 2) */
	float* tau;			 /* interpolation parameter τ (Jeong Eq. 1) */
} sere_particles;

/* Spring kinds: the low two bits name the layer, SERE_SPRING_VEIN flags a vein spring. */
enum
{
	SERE_SPRING_T = 0,
	SERE_SPRING_V = 1,
	SERE_SPRING_L = 2,
	SERE_SPRING_LAYER_MASK = 3,
	SERE_SPRING_VEIN = 4,
};

typedef struct sere_springs
{
	int32_t count;
	int32_t capacity;
	int32_t *a, *b; /* particle indices, a < b */
	float* rest;	/* current target length l^n (Jeong Eq. 12) */
	float* rest0;	/* rest length l^0 */
	uint8_t* kind;	/* SERE_SPRING_* */
} sere_springs;

/* Parameters of the double layer and of Sec. 3.3. */
typedef struct sere_layer_params
{
	double h_vein, h_surf;		   /* Voronoi offset along the triangle normal (Fig. 5e) */
	double omega_vein, omega_surf; /* shortest-path weights on vein and surface springs */
	double D;					   /* exponent of Jeong Eq. 1 */
	double m_min, m_max;		   /* mass range of Jeong Eq. 2 */
	double mu0;					   /* initial water ratio w = μ⁰ m */
} sere_layer_params;

sere_layer_params sere_layer_params_default( void );

/* The whole model. Springs are stored T first, then V, then L; within each kind sorted by
 * their first particle for locality. Triangle t owns Voronoi particle tri_count... index
 * triangle_particles + t. */
typedef struct sere_model
{
	sere_particles p;
	sere_springs s;
	int32_t triangle_particles; /* N */
	int32_t boundary_count;		/* B: triangle particles on the outline */
	int32_t triangle_count;		/* F = number of Voronoi particles */
	int32_t t_springs, v_springs, l_springs, vein_springs;
	int32_t base;	   /* particle index of the leaf base */
	int32_t* tri;	   /* 3 * triangle_count, counter-clockwise seen from +z at rest */
	float* h;		   /* thickness per triangle (signed, Fig. 5e) */
	uint8_t* tri_vein; /* nonzero when the triangle has a vein edge */
	uint8_t* boundary; /* per triangle particle: on the outline */
	uint8_t* vein;	   /* per triangle particle: on a vein */
	float *u, *v;	   /* per triangle particle: plane coordinates before shaping (texture) */
	double* d;		   /* per particle: weighted shortest distance from the base */
} sere_model;

/* Input of sere_model_from_triangles: a plane triangulation (counter-clockwise) of points,
 * the first boundary_count of which are the outline in order, plus flags of which undirected
 * edges lie on veins (vein_segments as index pairs). */
typedef struct sere_plane_mesh
{
	const double* x;
	const double* y;
	int32_t point_count;
	int32_t boundary_count;
	const int32_t* tri;
	int32_t triangle_count;
	const int32_t* vein_segments;
	int32_t vein_segment_count;
	int32_t base; /* index of the base point */
} sere_plane_mesh;

/* Builds the double layer: reorders the triangle particles and triangles along a Morton curve
 * for locality, places Voronoi particles at centroid + h·n, creates the T, V and L springs with
 * vein flags, then runs sere_model_assign_masses. The mesh must be a disk (every boundary
 * point used once on the outline); the counts then satisfy particles = 3N − B − 2 and
 * springs = 12N − 6B − 12. */
sere_status sere_model_from_triangles( const sere_plane_mesh* mesh, const sere_layer_params* params,
									   sere_model* model );

/* Weighted shortest distances from the base over the triangle layer's T springs (Dijkstra: the
 * exact shortest paths the paper computes with Bellman-Ford; a vein T spring weighs omega_vein,
 * the others omega_surf), τ (Jeong Eq. 1), m⁰ (Jeong Eq. 2) on the triangle layer, Voronoi
 * masses as the mean of their triangle's three, w = μ⁰ m, M = m − w. SERE_ERR_ARGUMENT for a
 * NULL argument or a parameter out of range or NaN (m_min > 0, m_max ≥ m_min, μ⁰ in [0, 1),
 * D, omega_vein and omega_surf > 0, all finite). */
sere_status sere_model_assign_masses( sere_model* model, const sere_layer_params* params );

/* Frees every array of a model made by sere_model_from_triangles or sere_model_build (model.h). */
void sere_model_destroy( sere_model* model );

/* N and B from exact particle and spring counts; SERE_ERR_COUNTS when no disk triangulation
 * gives them (non-integer, B < 3, or more than N − 0 boundary points). */
sere_status sere_counts_solve( int64_t particles, int64_t springs, int32_t* n, int32_t* b );

/* Mirrors the model through the horizontal plane halfway between its lowest and highest
 * particle (so the lowest point stays as low as it was): every z reflected, velocity z negated,
 * every thickness h negated, triangles unchanged (still counter-clockwise seen from +z). The
 * Voronoi layer then lies on the other side of the triangle layer: the same leaf turned over,
 * for a leaf that lies on the face its Voronoi layer is offset to. */
void sere_model_mirror_z( sere_model* model );

/* Moves the model along z so that its lowest particle sits at height ground: a leaf laid on the
 * ground. Nothing happens for a ground that is not finite. */
void sere_model_rest_on( sere_model* model, float ground );

/* The unit normal of triangle t from current positions (zero vector for a degenerate one). */
void sere_model_triangle_normal( const sere_model* model, int32_t t, float normal[3] );

#ifdef __cplusplus
}
#endif
