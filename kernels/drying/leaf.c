/* _GNU_SOURCE: sched_getaffinity for core/internal/team.h. */
#define _GNU_SOURCE

#include "drying/leaf.h"

#include "core/internal/team.h"

#include <float.h>
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

struct sere_leaf_sim
{
	int32_t threads; /* sere_leaf_set_threads */
	sere_model* model;
	sere_osmosis *osmosis_t, *osmosis_v;
	sere_pbd* pbd;
	sere_vbd* vbd;						/* the descent step (sere_leaf_params.descent) */
	int vbd_weights;					/* the compliance weights last set were all positive, as the descent needs */
	int pbd_rest_stale, vbd_rest_stale; /* the model's rest lengths changed since the solver took them */
	sere_bvh* bvh;
	sere_collide* collide;
	float* h_hat;		 /* ĥ where the last pass moved a corner; elsewhere an older finite value (0 at first), read
						  * only by the restore's check that every entry is finite */
	float *x0, *y0, *z0; /* triangle layer at the start of the frame: the contacts' sides */
	float *xc, *yc, *zc; /* triangle layer before the collision pass: which corners it moved */
	float* push;		 /* per particle: how far the ground pushed it up this frame (friction) */
	float *tx, *ty, *tz; /* the prediction the frame's projection starts from (step_residual) */
	float* weight;		 /* per spring: XPBD compliance weight by class */
	uint8_t* moved;		 /* per triangle-layer particle: moved by the collision response */
	float vein_weight, voronoi_weight, link_weight; /* the weights last given to the PBD workspace */
	int weights_set;
	float mean_rest; /* mean T rest length at rest: the length scale of the ground's slack */
	double* w0;
	double* w_frame; /* water at the start of the frame (the local Sec. 6 stop keeps it) */
	uint8_t* frozen; /* per particle: stopped by the local Sec. 6 stop, for good */
	double water0;
	int32_t contact_capacity;
	float thickness_scale; /* sere_leaf_thickness_scale, updated whenever rest lengths change */
	int desiccated;
	sere_team_tuner water_tuner; /* the osmosis's and the shrinkage's team or one thread (team.h) */
};

sere_leaf_params sere_leaf_params_default( void )
{
	sere_leaf_params params = {
		.dt = 0.002f,
		.gravity = { 0.0f, 0.0f, 0.0f },
		.ground = -INFINITY,
		.damping = 0.1f,
		.water_rate_t = -0.1,
		.water_rate_v = -0.1,
		.osmosis = sere_osmosis_params_default(),
		.shrink = { .sigma_vein = 0.5, .sigma_surf = 0.5, .alpha = 1.3, .m_min = 0.1, .min_length_ratio = 0.2 },
		.pbd = sere_pbd_params_default(),
		.vein_compliance = 0.1f,
		.voronoi_compliance = 1.0f,
		.link_compliance = 1.0f,
		.friction_static = 0.8f,
		.friction_kinetic = 0.6f,
		.collide = sere_collide_params_default(),
		.collisions = 1,
		.scale_thickness = 1,
		.restore_measured = 1,
		.soften = 0,
		.local_stop = 0,
		.step_residual = 1,
		.descent = 1,
		.descent_tolerance = 1e-6f,
		.descent_rho = 0.8f,
		.descent_delay = 2,
		.descent_warm = 1,
	};
	params.pbd.compliance = 4e-6f;
	/* Chebyshev semi-iteration (Wang 2015) of the XPBD sweeps is off (ρ = 0): the shapes it
	 * reaches are not bitwise those of the plain sweeps and drift from them on a frustrated leaf
	 * (tests/test_leaf.c). When turned on, 5 plain sweeps come first: on the Table 1 leaves over
	 * 200 frames ρ = 0.9 took the mean sweeps a frame from 53 to 23 (maple), 58 to 39 (plane
	 * tree) and 21 to 12 (wisteria); ρ = 0.95 oscillated on the maple until the cap, ρ = 0.8–0.85
	 * saved less. */
	params.pbd.chebyshev_delay = 5;
	/* A whole leaf of the harness's default 1500 points has longer edges than collide's
	 * ~4700-vertex reference: 0.004 at rest, shrinking with the sheet (scale_thickness). */
	params.collide.thickness = 0.004f;
	params.osmosis.tolerance = 1e-8;
	return params;
}

void sere_leaf_destroy( sere_leaf_sim* sim )
{
	if ( sim == NULL )
	{
		return;
	}
	sere_osmosis_destroy( sim->osmosis_t );
	sere_osmosis_destroy( sim->osmosis_v );
	sere_pbd_destroy( sim->pbd );
	sere_vbd_destroy( sim->vbd );
	sere_collide_destroy( sim->collide );
	sere_bvh_destroy( sim->bvh );
	sere_free( sim->h_hat );
	sere_free( sim->x0 );
	sere_free( sim->y0 );
	sere_free( sim->z0 );
	sere_free( sim->xc );
	sere_free( sim->yc );
	sere_free( sim->zc );
	sere_free( sim->push );
	sere_free( sim->tx );
	sere_free( sim->ty );
	sere_free( sim->tz );
	sere_free( sim->weight );
	sere_free( sim->moved );
	sere_free( sim->w0 );
	sere_free( sim->w_frame );
	sere_free( sim->frozen );
	free( sim );
}

/* The model's rest lengths changed: each step solver takes them when it next runs (a frame runs
 * one of the two, and a copy into the other would be a pass over every spring for nothing). */
static void rest_changed( sere_leaf_sim* sim )
{
	sim->pbd_rest_stale = sim->vbd_rest_stale = 1;
}

/* The PBD workspace with the model's current rest lengths. */
static sere_status pbd_current( sere_leaf_sim* sim )
{
	sere_status status = sim->pbd_rest_stale ? sere_pbd_set_rest( sim->pbd, sim->model->s.rest ) : SERE_OK;
	sim->pbd_rest_stale = status != SERE_OK;
	return status;
}

/* The descent's workspace with the model's current rest lengths. */
static sere_status vbd_current( sere_leaf_sim* sim )
{
	sere_status status = sim->vbd_rest_stale ? sere_vbd_set_rest( sim->vbd, sim->model->s.rest ) : SERE_OK;
	sim->vbd_rest_stale = status != SERE_OK;
	return status;
}

sere_status sere_leaf_create( sere_model* model, sere_leaf_sim** out )
{
	if ( model == NULL || out == NULL || model->p.count <= 0 )
	{
		return SERE_ERR_ARGUMENT;
	}
	sere_leaf_sim* sim = calloc( 1, sizeof( *sim ) );
	if ( sim == NULL )
	{
		return SERE_ERR_MEMORY;
	}
	sim->model = model;
	const int32_t n = model->triangle_particles, f = model->triangle_count;
	const sere_springs* s = &model->s;
	/* T layer: particles [0, N) over the T springs; V layer: [N, N+F) over the V springs. L
	 * springs carry no water (docs/DESIGN.md). */
	sere_status status = sere_osmosis_create( 0, n, s->a, s->b, model->t_springs, &sim->osmosis_t );
	if ( status == SERE_OK )
	{
		status = sere_osmosis_create( n, f, s->a + model->t_springs, s->b + model->t_springs, model->v_springs,
									  &sim->osmosis_v );
	}
	if ( status == SERE_OK )
	{
		status = sere_pbd_create( s->a, s->b, s->count, model->p.count, &sim->pbd );
	}
	if ( status == SERE_OK )
	{
		status = sere_vbd_create( s->a, s->b, s->count, model->p.count, &sim->vbd );
	}
	if ( status == SERE_OK )
	{
		rest_changed( sim );
		status = pbd_current( sim );
	}
	if ( status == SERE_OK )
	{
		status = sere_bvh_create( model->tri, f, n, model->p.x, model->p.y, model->p.z, &sim->bvh );
	}
	sim->contact_capacity = 8 * n;
	if ( status == SERE_OK )
	{
		status = sere_collide_create( sim->bvh, sim->contact_capacity, &sim->collide );
	}
	if ( status == SERE_OK )
	{
		/* the flat leaf as built: edges this close at rest are the sheet's own neighbours */
		status = sere_collide_set_rest( sim->collide, model->p.x, model->p.y, model->p.z );
	}
	sim->h_hat = sere_alloc( sizeof( float ) * (size_t) sere_pad( f ) );
	sim->w0 = sere_alloc( sizeof( double ) * (size_t) model->p.capacity );
	sim->w_frame = sere_alloc( sizeof( double ) * (size_t) model->p.capacity );
	sim->frozen = sere_alloc( (size_t) model->p.capacity );
	sim->x0 = sere_alloc( sizeof( float ) * (size_t) sere_pad( n ) );
	sim->y0 = sere_alloc( sizeof( float ) * (size_t) sere_pad( n ) );
	sim->z0 = sere_alloc( sizeof( float ) * (size_t) sere_pad( n ) );
	sim->xc = sere_alloc( sizeof( float ) * (size_t) sere_pad( n ) );
	sim->yc = sere_alloc( sizeof( float ) * (size_t) sere_pad( n ) );
	sim->zc = sere_alloc( sizeof( float ) * (size_t) sere_pad( n ) );
	sim->push = sere_alloc( sizeof( float ) * (size_t) model->p.capacity );
	sim->tx = sere_alloc( sizeof( float ) * (size_t) model->p.capacity );
	sim->ty = sere_alloc( sizeof( float ) * (size_t) model->p.capacity );
	sim->tz = sere_alloc( sizeof( float ) * (size_t) model->p.capacity );
	sim->weight = sere_alloc( sizeof( float ) * (size_t) sere_pad( s->count ) );
	sim->moved = sere_alloc( (size_t) sere_pad( n ) );
	if ( status == SERE_OK && ( sim->h_hat == NULL || sim->w0 == NULL || sim->w_frame == NULL || sim->frozen == NULL ||
								sim->x0 == NULL || sim->y0 == NULL || sim->z0 == NULL || sim->xc == NULL ||
								sim->yc == NULL || sim->zc == NULL || sim->push == NULL || sim->tx == NULL ||
								sim->ty == NULL || sim->tz == NULL || sim->weight == NULL || sim->moved == NULL ) )
	{
		status = SERE_ERR_MEMORY;
	}
	if ( status != SERE_OK )
	{
		sere_leaf_destroy( sim );
		return status;
	}
	memcpy( sim->w0, model->p.w, sizeof( double ) * (size_t) model->p.count );
	memset( sim->frozen, 0, (size_t) model->p.capacity );
	sim->thickness_scale = sere_leaf_thickness_scale( model );
	double rest_sum = 0.0;
	for ( int32_t k = 0; k < model->t_springs; ++k )
	{
		rest_sum += model->s.rest0[k];
	}
	sim->mean_rest = model->t_springs > 0 ? (float) ( rest_sum / model->t_springs ) : 0.0f;
	for ( int32_t i = 0; i < model->p.count; ++i )
	{
		sim->water0 += model->p.w[i];
	}
	*out = sim;
	return SERE_OK;
}

sere_status sere_leaf_set_threads( sere_leaf_sim* sim, int32_t threads )
{
	if ( sim == NULL || !sere_threads_valid( threads ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	/* The collision workspace may need buffers for more threads: the one call that allocates. */
	sere_status status = sere_collide_set_threads( sim->collide, threads );
	if ( status != SERE_OK )
	{
		return status;
	}
	sim->threads = threads;
	sere_osmosis_set_threads( sim->osmosis_t, threads );
	sere_osmosis_set_threads( sim->osmosis_v, threads );
	sere_pbd_set_threads( sim->pbd, threads );
	sere_vbd_set_threads( sim->vbd, threads );
	sere_bvh_set_threads( sim->bvh, threads );
	return SERE_OK;
}

void sere_leaf_relative_water( const sere_leaf_sim* sim, float* out )
{
	const sere_particles* p = &sim->model->p;
	for ( int32_t i = 0; i < p->count; ++i )
	{
		out[i] = sim->w0[i] > 0.0 ? (float) ( p->w[i] / sim->w0[i] ) : 0.0f;
	}
}

sere_shape_input sere_leaf_shape_input( const sere_model* model, double ground )
{
	sere_shape_input in = sere_shape_input_default();
	in.x = model->p.x, in.y = model->p.y, in.z = model->p.z;
	in.u = model->u, in.v = model->v;
	in.vertex_count = model->triangle_particles;
	in.tri = model->tri;
	in.triangle_count = model->triangle_count;
	/* the T springs come first and are exactly the triangle edges; SERE_SPRING_VEIN is the only
	 * bit a T spring sets */
	in.edge_a = model->s.a, in.edge_b = model->s.b;
	in.edge_vein = model->s.kind;
	in.edge_count = model->t_springs;
	in.boundary = model->boundary;
	in.ground = ground;
	return in;
}

/* Sec. 6 where it happens: the paper stops flow and shrinkage in both layers once one layer is
 * desiccated, so that the other does not catch up and flatten the leaf again. Applied to the
 * whole leaf at once, that stop comes only when the last particle of a layer runs dry, long
 * after both layers have dried alike almost everywhere (water is lost at the same rate per
 * particle, so light particles of both layers run dry early). Applied locally, a triangle whose
 * Voronoi particle has run dry stops its corners, and a corner that has run dry stops the
 * Voronoi particles of its triangles: each stopped particle keeps, from then on, the water and
 * mass it had at the start of the frame, and its springs keep their rest lengths (Jeong Eq. 12 sees no
 * change of mass). The layer that dries first keeps the curvature it made. */
static void local_stop( sere_leaf_sim* sim )
{
	sere_model* model = sim->model;
	sere_particles* p = &model->p;
	const int32_t n = model->triangle_particles;
	for ( int32_t t = 0; t < model->triangle_count; ++t )
	{
		const int32_t* v = model->tri + 3 * t;
		const int32_t voronoi = n + t;
		if ( p->w[voronoi] <= 0.0 )
		{
			sim->frozen[v[0]] = sim->frozen[v[1]] = sim->frozen[v[2]] = 1;
		}
		if ( p->w[v[0]] <= 0.0 || p->w[v[1]] <= 0.0 || p->w[v[2]] <= 0.0 )
		{
			sim->frozen[voronoi] = 1;
		}
	}
	for ( int32_t i = 0; i < p->count; ++i )
	{
		if ( sim->frozen[i] && p->w[i] > 0.0 )
		{
			p->w[i] = sim->w_frame[i];
			p->m[i] = p->M[i] + p->w[i]; /* back to its frame-start mass (Jeong Eq. 10 is osmosis.c's) */
		}
	}
}

static double layer_water( const double* w, int32_t first, int32_t count )
{
	double sum = 0.0;
	for ( int32_t i = first; i < first + count; ++i )
	{
		sum += w[i];
	}
	return sum;
}

float sere_leaf_thickness_scale( const sere_model* model )
{
	double rest = 0.0, rest0 = 0.0;
	for ( int32_t k = 0; k < model->t_springs; ++k )
	{
		rest += model->s.rest[k];
		rest0 += model->s.rest0[k];
	}
	return rest0 > 0.0 ? (float) ( rest / rest0 ) : 1.0f;
}

/* The bits of a non-negative float order as the float does: a maximum taken over them is the
 * float maximum, as an integer reduction, which every OpenMP runtime combines exactly (clang's
 * libomp gave a different float max for 1 and 2 threads over the same values). */
static uint32_t order_bits( float value )
{
	uint32_t bits;
	memcpy( &bits, &value, sizeof( bits ) );
	return bits;
}

static float bits_value( uint32_t bits )
{
	float value;
	memcpy( &value, &bits, sizeof( value ) );
	return value;
}

/* Puts particles below the ground onto it and adds how far each was pushed to push[]; returns
 * the largest push of this call (the same for every thread count). */
static float ground_contact( float* pz, float* push, int32_t count, float ground, int32_t threads )
{
	uint32_t largest = 0;
#pragma omp parallel for num_threads( sere_team_for( threads ) ) schedule( static ) reduction( max : largest )
	for ( int32_t i = 0; i < count; ++i )
	{
		float depth = ground - pz[i];
		depth = depth > 0.0f ? depth : 0.0f;
		pz[i] += depth;
		push[i] += depth;
		uint32_t bits = order_bits( depth );
		largest = bits > largest ? bits : largest;
	}
	return bits_value( largest );
}

/* Coulomb friction of the ground as a position correction (Macklin et al. 2014, Sec. 6.1): the
 * ground's push d_n this frame bounds the tangential displacement it can hold. A particle whose
 * displacement along the ground Δx_t is within μ_s d_n sticks (Δx_t removed); a larger one slides
 * with Δx_t shortened by μ_k d_n. Returns the number of particles in contact. */
static int32_t ground_friction( sere_particles* p, const float* push, int32_t count, float mu_static, float mu_kinetic,
								int32_t threads )
{
	int32_t touching = 0;
#pragma omp parallel for num_threads( sere_team_for( threads ) ) schedule( static ) reduction( + : touching )
	for ( int32_t i = 0; i < count; ++i )
	{
		if ( !( push[i] > 0.0f ) )
		{
			continue;
		}
		touching += 1;
		float dx = p->px[i] - p->x[i], dy = p->py[i] - p->y[i];
		float slide = sqrtf( dx * dx + dy * dy );
		float keep = slide <= mu_static * push[i] ? 0.0f : 1.0f - mu_kinetic * push[i] / slide;
		keep = keep > 0.0f ? keep : 0.0f;
		p->px[i] = p->x[i] + keep * dx;
		p->py[i] = p->y[i] + keep * dy;
	}
	return touching;
}

/* max |C/l| over every spring at the predicted positions (an integer maximum of the bits, as in
 * ground_contact; a NaN strain orders above every number). */
static float largest_strain( const sere_model* model, int32_t threads )
{
	const sere_springs* s = &model->s;
	const sere_particles* p = &model->p;
	uint32_t largest = 0;
	/* scalar: in lanes the six position gathers cost 3× the loop on the AVX-512 machine */
#pragma omp parallel for num_threads( sere_team_for( threads ) ) schedule( static ) reduction( max : largest )
	for ( int32_t k = 0; k < s->count; ++k )
	{
		int32_t a = s->a[k], b = s->b[k];
		float dx = p->px[b] - p->px[a], dy = p->py[b] - p->py[a], dz = p->pz[b] - p->pz[a];
		float strain = fabsf( sqrtf( ( dx * dx + dy * dy ) + dz * dz ) - s->rest[k] ) / s->rest[k];
		uint32_t bits = order_bits( strain );
		largest = bits > largest ? bits : largest;
	}
	return bits_value( largest );
}

/* Compliance weights by spring class: vein springs (T and V) and L springs relative to the
 * blade's. Set again only when the parameters change. */
static sere_status set_weights( sere_leaf_sim* sim, const sere_leaf_params* params )
{
	if ( sim->weights_set && sim->vein_weight == params->vein_compliance &&
		 sim->voronoi_weight == params->voronoi_compliance && sim->link_weight == params->link_compliance )
	{
		return SERE_OK;
	}
	const sere_springs* s = &sim->model->s;
	for ( int32_t k = 0; k < s->count; ++k )
	{
		int layer = s->kind[k] & SERE_SPRING_LAYER_MASK;
		float weight = 1.0f;
		if ( layer == SERE_SPRING_L )
		{
			weight = params->link_compliance;
		}
		else if ( s->kind[k] & SERE_SPRING_VEIN )
		{
			weight = params->vein_compliance;
		}
		else if ( layer == SERE_SPRING_V )
		{
			weight = params->voronoi_compliance;
		}
		sim->weight[k] = weight;
	}
	sere_status status = sere_pbd_set_compliance_weights( sim->pbd, sim->weight );
	sim->weights_set = status == SERE_OK;
	/* a zero weight (a rigid class) is XPBD's to take; a descent refuses it at its step */
	sim->vbd_weights = sere_vbd_set_compliance_weights( sim->vbd, sim->weight ) == SERE_OK;
	sim->vein_weight = params->vein_compliance;
	sim->voronoi_weight = params->voronoi_compliance;
	sim->link_weight = params->link_compliance;
	return status;
}

/* The prediction the frame's step starts from, kept for the step residual's measure when asked;
 * returns the seconds it took (a measure beside the frame, kept out of its times). */
static double keep_prediction( sere_leaf_sim* sim, const sere_leaf_params* params )
{
	const sere_particles* p = &sim->model->p;
	const double start = omp_get_wtime();
	if ( params->step_residual )
	{
		memcpy( sim->tx, p->px, sizeof( float ) * (size_t) p->count );
		memcpy( sim->ty, p->py, sizeof( float ) * (size_t) p->count );
		memcpy( sim->tz, p->pz, sizeof( float ) * (size_t) p->count );
	}
	return omp_get_wtime() - start;
}

/* Lines 17–22 as the descent of the XPBD step's energy (sere_leaf_params.descent, solve/vbd.h):
 * the same compliances, weights and cap; the ground as the descent's bound, its push for the
 * friction that follows. */
static sere_status descend( sere_leaf_sim* sim, const sere_leaf_params* params, const sere_pbd_params* pbd,
							sere_leaf_stats* stats, double* aside )
{
	sere_particles* p = &sim->model->p;
	if ( !sim->vbd_weights )
	{
		return SERE_ERR_ARGUMENT;
	}
	sere_status status = vbd_current( sim );
	if ( status != SERE_OK )
	{
		return status;
	}
	const float length = sim->mean_rest * sim->thickness_scale;
	sere_vbd_params step = sere_vbd_params_default();
	step.dt = pbd->dt;
	step.compliance = pbd->compliance;
	step.tolerance = params->descent_tolerance * length;
	step.max_iterations = pbd->max_iterations;
	step.chebyshev_rho = params->descent_rho;
	step.chebyshev_delay = params->descent_delay;
	step.warm_start = params->descent_warm;
	step.ground = isfinite( params->ground ) ? params->ground : -INFINITY;
	*aside = keep_prediction( sim, params );
	sere_vbd_report report;
	status = sere_vbd_step( sim->vbd, p->px, p->py, p->pz, p->inv_m, &step, &report );
	if ( status == SERE_OK )
	{
		status = sere_vbd_ground_push( sim->vbd, sim->push );
	}
	if ( status == SERE_OK && params->step_residual )
	{
		const double start = omp_get_wtime();
		sere_vbd_residuals r;
		status =
			sere_vbd_step_residual( sim->vbd, p->px, p->py, p->pz, sim->tx, sim->ty, sim->tz, p->inv_m, &step, &r );
		if ( status == SERE_OK )
		{
			stats->step_primal = r.constraint > 0.0 ? (float) ( r.primal / r.constraint ) : 0.0f;
		}
		*aside += omp_get_wtime() - start;
	}
	stats->pbd_iterations = report.iterations;
	stats->residual = length > 0.0f ? report.max_move / length : report.max_move;
	stats->pbd_converged = !report.hit_cap;
	stats->pbd_hit_cap = report.hit_cap;
	return status;
}

/* Lines 17–22: the descent (descend, above) unless descent = 0 or the paper's PBD; as one XPBD
 * step, the projection meets the ground itself (sere_pbd_params.ground:
 * when the sweeps converge it puts the particles below the ground onto it and goes on with the
 * same multipliers while that pushed more than the slack), so one call is the step; converged
 * when the residual and the ground are both met before the cap. The paper's mode projects once
 * (with its stall rule) and then meets the ground. */
static sere_status project( sere_leaf_sim* sim, const sere_leaf_params* params, const sere_pbd_params* pbd,
							sere_leaf_stats* stats, double* aside )
{
	sere_particles* p = &sim->model->p;
	const int ground = isfinite( params->ground );
	sere_pbd_report report = { 0, 0.0f, 0 };
	stats->step_primal = NAN;
	if ( params->descent && pbd->compliance > 0.0f )
	{
		return descend( sim, params, pbd, stats, aside );
	}
	sere_status status = pbd_current( sim );
	if ( status != SERE_OK )
	{
		return status;
	}
	if ( pbd->compliance == 0.0f )
	{
		status =
			sere_pbd_project_stalling( sim->pbd, p->px, p->py, p->pz, p->inv_m, pbd, &report, &stats->pbd_stalled );
		if ( ground )
		{
			ground_contact( p->pz, sim->push, p->count, params->ground, sim->threads );
		}
		stats->pbd_iterations = report.iterations;
		stats->residual = report.max_strain;
		stats->pbd_hit_cap = report.hit_cap;
		stats->pbd_converged = !report.hit_cap && !stats->pbd_stalled;
		return status;
	}
	sere_pbd_params step = *pbd;
	step.warm = 0;
	step.ground = ground ? params->ground : -INFINITY;
	step.ground_slack = pbd->tolerance * sim->mean_rest * sim->thickness_scale;
	*aside = keep_prediction( sim, params );
	status = sere_pbd_project( sim->pbd, p->px, p->py, p->pz, p->inv_m, &step, &report );
	if ( status != SERE_OK )
	{
		return status;
	}
	if ( ground )
	{
		sere_pbd_ground_push( sim->pbd, sim->push );
	}
	if ( params->step_residual )
	{
		const double start = omp_get_wtime();
		sere_pbd_residuals r;
		status = sere_pbd_step_residual( sim->pbd, p->px, p->py, p->pz, sim->tx, sim->ty, sim->tz, p->inv_m, &r );
		if ( status != SERE_OK )
		{
			return status;
		}
		stats->step_primal = r.constraint > 0.0 ? (float) ( r.primal / r.constraint ) : 0.0f;
		*aside += omp_get_wtime() - start;
	}
	stats->pbd_iterations = report.iterations;
	stats->residual = report.max_strain;
	stats->pbd_converged = !report.hit_cap;
	stats->pbd_hit_cap = report.hit_cap;
	return SERE_OK;
}

/* Lines 2–6: osmotic flow on each layer, then the masses (Jeong Eq. 10, inside the kernel).
 * SERE_ERR_NO_CONVERGE of a layer's CG is no failure: the frame goes on with its water. */
static sere_status osmotic_flow( sere_leaf_sim* sim, const sere_leaf_params* params, sere_leaf_stats* stats )
{
	sere_particles* p = &sim->model->p;
	const int32_t n = sim->model->triangle_particles, f = sim->model->triangle_count;
	memcpy( sim->w_frame, p->w, sizeof( double ) * (size_t) p->count );
	sere_osmosis_params layer = params->osmosis;
	layer.dt = params->dt;
	sere_osmosis_report report;
	layer.water_rate = params->water_rate_t;
	sere_status status =
		sere_osmosis_step( sim->osmosis_t, p->x, p->y, p->z, p->tau, p->M, p->w, p->m, &layer, &report );
	stats->cg_iterations_t = report.iterations;
	if ( status != SERE_OK && status != SERE_ERR_NO_CONVERGE )
	{
		return status;
	}
	layer.water_rate = params->water_rate_v;
	status = sere_osmosis_step( sim->osmosis_v, p->x, p->y, p->z, p->tau, p->M, p->w, p->m, &layer, &report );
	stats->cg_iterations_v = report.iterations;
	if ( status != SERE_OK && status != SERE_ERR_NO_CONVERGE )
	{
		return status;
	}
	if ( params->local_stop )
	{
		local_stop( sim );
	}
	/* Sec. 6: when either layer is completely desiccated, flow and shrinkage stop so the
	 * leaf does not return to its flat shape. */
	sim->desiccated = layer_water( p->w, 0, n ) <= 0.0 || layer_water( p->w, n, f ) <= 0.0;
	return status;
}

/* Lines 7–9: rest lengths from masses (Jeong Eq. 11–12), handed to the PBD workspace. */
static sere_status shrink_rest( sere_leaf_sim* sim, const sere_leaf_params* params, int32_t threads )
{
	sere_model* model = sim->model;
	sere_status status = sere_shrink( model->s.a, model->s.b, model->s.kind, model->s.rest0, model->s.rest, 0,
									  model->s.count, model->p.m, model->p.m0, &params->shrink, threads );
	if ( status == SERE_OK )
	{
		rest_changed( sim );
		sim->thickness_scale = sere_leaf_thickness_scale( model );
	}
	return status;
}

/* Line 23: self-collision of the triangle layer, with the layer kept as it was (Jeong Sec. 5.3
 * measures ĥ on it), so the caller sees which corners the response moved. */
static sere_status self_collide( sere_leaf_sim* sim, const sere_leaf_params* params, sere_leaf_stats* stats )
{
	sere_model* model = sim->model;
	sere_particles* p = &model->p;
	const int32_t n = model->triangle_particles;
	memcpy( sim->xc, p->x, sizeof( float ) * (size_t) n );
	memcpy( sim->yc, p->y, sizeof( float ) * (size_t) n );
	memcpy( sim->zc, p->z, sizeof( float ) * (size_t) n );
	sere_collide_state state = { p->x, p->y, p->z, p->vx, p->vy, p->vz, p->inv_m, sim->x0, sim->y0, sim->z0 };
	sere_collide_params collide = params->collide;
	collide.dt = params->dt;
	if ( params->scale_thickness )
	{
		collide.thickness *= sim->thickness_scale;
	}
	sere_collide_stats collide_stats;
	sere_status status = sere_collide_resolve( sim->collide, sim->bvh, &state, &collide, &collide_stats );
	/* A crumpled leaf can have more contacts than the workspace holds: grow it (rare, so
	 * the allocation stays out of the steady state) and run the pass again. */
	for ( int grow = 0; status == SERE_ERR_CAPACITY && grow < 8; ++grow )
	{
		sim->contact_capacity *= 2;
		status = sere_collide_reserve( sim->collide, sim->contact_capacity );
		if ( status == SERE_OK )
		{
			status = sere_collide_resolve( sim->collide, sim->bvh, &state, &collide, &collide_stats );
		}
	}
	if ( status != SERE_OK )
	{
		return status;
	}
	stats->contacts = collide_stats.contacts;
	stats->edge_contacts = collide_stats.edge_contacts;
	stats->unresolved = collide_stats.unresolved;
	stats->collision_thickness = collide.thickness;
	return SERE_OK;
}

/* Lines 24–27: the Voronoi particles of the triangles the pass moved back on their normals (Jeong
 * Eq. 14), with ĥ as it was before the pass (line 14, Sec. 5.3). Only those triangles read ĥ, so
 * only theirs is measured, from the corners saved before the pass: the same bits as measuring
 * every triangle before it. A NaN or infinity elsewhere in the layers has already failed the
 * step: the projection's confirming measure reads every spring, each Voronoi particle's links
 * among them. */
static sere_status restore_moved( sere_leaf_sim* sim, const sere_leaf_params* params )
{
	sere_model* model = sim->model;
	sere_particles* p = &model->p;
	const int32_t n = model->triangle_particles, f = model->triangle_count;
#pragma omp parallel for simd num_threads( sere_team_for( sim->threads ) ) schedule( static )
	for ( int32_t i = 0; i < n; ++i )
	{
		sim->moved[i] = ( p->x[i] != sim->xc[i] ) | ( p->y[i] != sim->yc[i] ) | ( p->z[i] != sim->zc[i] );
	}
	if ( params->restore_measured )
	{
		sere_status status = sere_collide_measure_h_moved( sim->xc, sim->yc, sim->zc, p->x, p->y, p->z, model->tri, f,
														   n, sim->moved, sim->h_hat, sim->threads );
		if ( status != SERE_OK )
		{
			return status;
		}
	}
	return sere_collide_restore_voronoi_moved( p->x, p->y, p->z, p->vx, p->vy, p->vz, model->tri, f, n,
											   params->restore_measured ? sim->h_hat : model->h, sim->moved, params->dt,
											   sim->threads );
}

/* The step's PBD parameters: the frame's dt, and with soften the stiffness eased as the leaf
 * dries (a quarter of it when dry), by the relative water content of the whole leaf. */
static sere_pbd_params projection_params( const sere_leaf_sim* sim, const sere_leaf_params* params )
{
	const sere_particles* p = &sim->model->p;
	sere_pbd_params pbd = params->pbd;
	pbd.dt = params->dt;
	if ( params->soften && sim->water0 > 0.0 )
	{
		double rwc = ( layer_water( p->w, 0, p->count ) ) / sim->water0;
		pbd.stiffness = (float) ( params->pbd.stiffness * ( 0.25 + 0.75 * fmin( 1.0, rwc ) ) );
	}
	return pbd;
}

/* The frame's water per layer and relative to the start, and its wall time by part from the
 * clock readings before osmosis, dynamics, collisions and after. */
static void report_frame( const sere_leaf_sim* sim, const double wall[4], sere_leaf_stats* stats )
{
	const sere_particles* p = &sim->model->p;
	const int32_t n = sim->model->triangle_particles, f = sim->model->triangle_count;
	stats->water_t = layer_water( p->w, 0, n );
	stats->water_v = layer_water( p->w, n, f );
	stats->relative_water = sim->water0 > 0.0 ? ( stats->water_t + stats->water_v ) / sim->water0 : 0.0;
	stats->desiccated = sim->desiccated;
	stats->osmosis_ms = 1e3 * ( wall[1] - wall[0] );
	stats->dynamics_ms = 1e3 * ( wall[2] - wall[1] );
	stats->collisions_ms = 1e3 * ( wall[3] - wall[2] );
	stats->total_ms = 1e3 * ( wall[3] - wall[0] );
}

/* Lines 2–9: osmosis, then shrinkage; both stop for good once a layer is dry (Sec. 6). Their
 * loops meet at OpenMP's barriers and the CG's, and in the other guest's spells (team.h) two
 * threads ran them at twice the time of one: they run on one thread while their team has been
 * measured the slower (sere_team_tuner, a frame the unit); the frame's other phases keep the
 * leaf's count. *t1 is when the osmosis ended. */
static sere_status water_phase( sere_leaf_sim* sim, const sere_leaf_params* params, sere_leaf_stats* stats, double* t1 )
{
	const double t0 = omp_get_wtime();
	const int water = sere_tuner_team( &sim->water_tuner, sere_team_for( sim->threads ) );
	sere_osmosis_set_threads( sim->osmosis_t, water );
	sere_osmosis_set_threads( sim->osmosis_v, water );
	const int wet = !sim->desiccated;
	if ( wet )
	{
		const sere_status status = osmotic_flow( sim, params, stats );
		if ( status != SERE_OK && status != SERE_ERR_NO_CONVERGE )
		{
			return status;
		}
	}
	*t1 = omp_get_wtime();
	if ( !sim->desiccated )
	{
		const sere_status status = shrink_rest( sim, params, water );
		if ( status != SERE_OK )
		{
			return status;
		}
	}
	if ( wet )
	{
		sere_tuner_record( &sim->water_tuner, water, omp_get_wtime() - t0, 1.0 );
	}
	return SERE_OK;
}

sere_status sere_leaf_step( sere_leaf_sim* sim, const sere_leaf_params* params, sere_leaf_stats* stats )
{
	if ( stats == NULL )
	{
		return SERE_ERR_ARGUMENT;
	}
	memset( stats, 0, sizeof( *stats ) );
	/* damping is a fraction of the velocity: outside [0, 1] (or NaN) it would grow or poison
	 * every velocity; the ground is a height or −∞ for none */
	if ( sim == NULL || params == NULL || !( params->dt > 0.0f ) || !( params->pbd.compliance >= 0.0f ) ||
		 !( params->vein_compliance >= 0.0f ) || !( params->voronoi_compliance >= 0.0f ) ||
		 !( params->link_compliance >= 0.0f ) || !( params->friction_static >= 0.0f ) ||
		 !( params->friction_kinetic >= 0.0f ) || !( params->damping >= 0.0f && params->damping <= 1.0f ) ||
		 isnan( params->ground ) || params->ground == INFINITY )
	{
		return SERE_ERR_ARGUMENT;
	}
	sere_model* model = sim->model;
	sere_particles* p = &model->p;
	const int32_t n = model->triangle_particles;
	sere_status status = SERE_OK;
	double t0 = omp_get_wtime();

	double t1 = t0;
	status = water_phase( sim, params, stats, &t1 );
	if ( status != SERE_OK )
	{
		return status;
	}
	status = set_weights( sim, params );
	if ( status != SERE_OK )
	{
		return status;
	}
	/* Lighter particles move more: PBD weights by the current inverse mass. */
#pragma omp parallel for simd num_threads( sere_team_for( sim->threads ) ) schedule( static )
	for ( int32_t i = 0; i < p->count; ++i )
	{
		p->inv_m[i] = (float) ( 1.0 / p->m[i] );
		sim->push[i] = 0.0f;
	}
	/* Lines 10–13: gravity and prediction. The step's inertia anchor must not lie under the
	 * ground: the ground holds the prediction up before the projection starts. */
	sere_pbd_predict( p->count, p->x, p->y, p->z, p->vx, p->vy, p->vz, p->px, p->py, p->pz, p->inv_m, params->gravity,
					  params->dt, sim->threads );
	if ( isfinite( params->ground ) )
	{
		ground_contact( p->pz, sim->push, p->count, params->ground, sim->threads );
	}

	/* Lines 17–22: projection of the T, V and L constraints, one colored Gauss–Seidel. */
	sere_pbd_params pbd = projection_params( sim, params );
	double aside = 0.0; /* the measures beside the frame (step residual, largest strain), kept out of its times */
	status = project( sim, params, &pbd, stats, &aside );
	if ( status != SERE_OK )
	{
		return status;
	}
	if ( isfinite( params->ground ) )
	{
		stats->grounded =
			ground_friction( p, sim->push, p->count, params->friction_static, params->friction_kinetic, sim->threads );
	}
	/* a measure beside the frame, like the step residual: not part of Algorithm 1, kept out of
	 * its times */
	const double measured = omp_get_wtime();
	stats->max_strain = largest_strain( model, sim->threads );
	aside += omp_get_wtime() - measured;
	/* the start of the frame, before sere_pbd_finish moves it: where each contact's vertex was */
	if ( params->collisions && params->collide.thickness > 0.0f )
	{
		memcpy( sim->x0, p->x, sizeof( float ) * (size_t) n );
		memcpy( sim->y0, p->y, sizeof( float ) * (size_t) n );
		memcpy( sim->z0, p->z, sizeof( float ) * (size_t) n );
	}
	sere_pbd_finish( p->count, p->x, p->y, p->z, p->vx, p->vy, p->vz, p->px, p->py, p->pz, params->dt, sim->threads );
	const float keep = 1.0f - params->damping;
#pragma omp parallel for simd num_threads( sere_team_for( sim->threads ) ) schedule( static )
	for ( int32_t i = 0; i < p->count; ++i )
	{
		p->vx[i] *= keep;
		p->vy[i] *= keep;
		p->vz[i] *= keep;
	}
	double t2 = omp_get_wtime();

	/* Line 23: self-collision of the triangle layer; lines 24–27: the Voronoi particles of the
	 * triangles it moved back on their normals. */
	if ( params->collisions && params->collide.thickness > 0.0f )
	{
		status = self_collide( sim, params, stats );
		if ( status != SERE_OK )
		{
			return status;
		}
		status = restore_moved( sim, params );
		if ( status != SERE_OK )
		{
			return status;
		}
	}
	double t3 = omp_get_wtime();

	const double wall[4] = { t0, t1, t2 - aside, t3 - aside };
	report_frame( sim, wall, stats );
	return SERE_OK;
}

sere_status sere_leaf_shape_initial( sere_leaf_sim* sim, float crease, float curl, const sere_pbd_params* pbd )
{
	/* refused before anything changes: every new rest length must stay positive */
	if ( sim == NULL || pbd == NULL || !( crease < 1.0f && crease > -FLT_MAX ) || !( curl > -1.0f && curl < FLT_MAX ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	sere_model* model = sim->model;
	sere_springs* s = &model->s;
	sere_particles* p = &model->p;
	for ( int32_t k = model->t_springs; k < model->t_springs + model->v_springs; ++k )
	{
		s->rest[k] = s->rest0[k] * ( ( s->kind[k] & SERE_SPRING_VEIN ) ? 1.0f - crease : 1.0f + curl );
	}
	rest_changed( sim );
	sere_status status = pbd_current( sim );
	if ( status != SERE_OK )
	{
		return status;
	}
	memcpy( p->px, p->x, sizeof( float ) * (size_t) p->count );
	memcpy( p->py, p->y, sizeof( float ) * (size_t) p->count );
	memcpy( p->pz, p->z, sizeof( float ) * (size_t) p->count );
	sere_pbd_report report;
	status = sere_pbd_project( sim->pbd, p->px, p->py, p->pz, p->inv_m, pbd, &report );
	if ( status != SERE_OK )
	{
		return status;
	}
	/* The shaped leaf is the new rest state: positions at rest, l⁰ from the shaped lengths. */
	memcpy( p->x, p->px, sizeof( float ) * (size_t) p->count );
	memcpy( p->y, p->py, sizeof( float ) * (size_t) p->count );
	memcpy( p->z, p->pz, sizeof( float ) * (size_t) p->count );
	for ( int32_t k = 0; k < s->count; ++k )
	{
		float dx = p->x[s->b[k]] - p->x[s->a[k]], dy = p->y[s->b[k]] - p->y[s->a[k]],
			  dz = p->z[s->b[k]] - p->z[s->a[k]];
		s->rest0[k] = s->rest[k] = sqrtf( dx * dx + dy * dy + dz * dz );
	}
	sim->thickness_scale = sere_leaf_thickness_scale( model );
	rest_changed( sim );
	status = pbd_current( sim );
	if ( status == SERE_OK )
	{
		status = sere_bvh_build( sim->bvh, p->x, p->y, p->z );
	}
	if ( status == SERE_OK )
	{
		status = sere_collide_set_rest( sim->collide, p->x, p->y, p->z );
	}
	return status;
}
