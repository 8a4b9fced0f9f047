#include "leaf.h"

#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

struct sere_leaf_sim
{
	sere_model* model;
	sere_osmosis *osmosis_t, *osmosis_v;
	sere_pbd* pbd;
	sere_bvh* bvh;
	sere_collide* collide;
	float* h_hat;
	float *x0, *y0, *z0; /* triangle layer at the start of the frame: the contacts' sides */
	double* w0;
	double water0;
	int32_t contact_capacity;
	float thickness_scale; /* sere_leaf_thickness_scale, updated whenever rest lengths change */
	int desiccated;
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
		.collide = sere_collide_params_default(),
		.collisions = 1,
		.scale_thickness = 1,
		.restore_measured = 1,
		.soften = 0,
		.pbd_stall = 0.0f,
		.restore_conserving = 0,
	};
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
	sere_collide_destroy( sim->collide );
	sere_bvh_destroy( sim->bvh );
	sere_free( sim->h_hat );
	sere_free( sim->x0 );
	sere_free( sim->y0 );
	sere_free( sim->z0 );
	sere_free( sim->w0 );
	free( sim );
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
	 * springs carry no water (DESIGN.md). */
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
		status = sere_pbd_set_rest( sim->pbd, s->rest );
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
	sim->h_hat = sere_alloc( sizeof( float ) * (size_t) sere_pad( f ) );
	sim->w0 = sere_alloc( sizeof( double ) * (size_t) model->p.capacity );
	sim->x0 = sere_alloc( sizeof( float ) * (size_t) sere_pad( n ) );
	sim->y0 = sere_alloc( sizeof( float ) * (size_t) sere_pad( n ) );
	sim->z0 = sere_alloc( sizeof( float ) * (size_t) sere_pad( n ) );
	if ( status == SERE_OK &&
		 ( sim->h_hat == NULL || sim->w0 == NULL || sim->x0 == NULL || sim->y0 == NULL || sim->z0 == NULL ) )
	{
		status = SERE_ERR_MEMORY;
	}
	if ( status != SERE_OK )
	{
		sere_leaf_destroy( sim );
		return status;
	}
	memcpy( sim->w0, model->p.w, sizeof( double ) * (size_t) model->p.count );
	sim->thickness_scale = sere_leaf_thickness_scale( model );
	for ( int32_t i = 0; i < model->p.count; ++i )
	{
		sim->water0 += model->p.w[i];
	}
	*out = sim;
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

/* The projection of lines 17–22 with the optional stall rule (sere_leaf_params.pbd_stall): the
 * cap's sweeps run in chunks of SERE_LEAF_STALL_WINDOW, and the frame stops when a chunk ends
 * with max |C/l| (of its last sweep) above (1 − stall) times the previous chunk's. Gauss–Seidel
 * state carries over between chunks, so without a stall the positions equal one call's. */
static sere_status project( sere_pbd* pbd, sere_particles* p, const sere_pbd_params* params, float stall,
							sere_pbd_report* report, int* stalled )
{
	*stalled = 0;
	if ( stall <= 0.0f || params->compliance > 0.0f || params->linear_stiffness )
	{
		return sere_pbd_project( pbd, p->px, p->py, p->pz, p->inv_m, params, report );
	}
	sere_pbd_params chunk = *params;
	int32_t done = 0;
	float previous = INFINITY;
	while ( done < params->max_iterations )
	{
		int32_t left = params->max_iterations - done;
		chunk.max_iterations = left < SERE_LEAF_STALL_WINDOW ? left : SERE_LEAF_STALL_WINDOW;
		sere_status status = sere_pbd_project( pbd, p->px, p->py, p->pz, p->inv_m, &chunk, report );
		if ( status != SERE_OK )
		{
			return status;
		}
		done += report->iterations;
		if ( !report->hit_cap )
		{
			break;
		}
		if ( report->max_strain > ( 1.0f - stall ) * previous )
		{
			*stalled = done < params->max_iterations;
			break;
		}
		previous = report->max_strain;
	}
	report->iterations = done;
	report->hit_cap = report->hit_cap && !*stalled;
	return SERE_OK;
}

sere_status sere_leaf_step( sere_leaf_sim* sim, const sere_leaf_params* params, sere_leaf_stats* stats )
{
	memset( stats, 0, sizeof( *stats ) );
	if ( sim == NULL || params == NULL || !( params->dt > 0.0f ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	sere_model* model = sim->model;
	sere_particles* p = &model->p;
	const int32_t n = model->triangle_particles, f = model->triangle_count;
	sere_status status = SERE_OK;
	double t0 = omp_get_wtime();

	/* Lines 2–6: osmotic flow on each layer, then the masses (Eq. 10, inside the kernel). */
	if ( !sim->desiccated )
	{
		sere_osmosis_params layer = params->osmosis;
		layer.dt = params->dt;
		sere_osmosis_report report;
		layer.water_rate = params->water_rate_t;
		status = sere_osmosis_step( sim->osmosis_t, p->x, p->y, p->z, p->tau, p->M, p->w, p->m, &layer, &report );
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
		/* Sec. 6: when either layer is completely desiccated, flow and shrinkage stop so the
		 * leaf does not return to its flat shape. */
		sim->desiccated = layer_water( p->w, 0, n ) <= 0.0 || layer_water( p->w, n, f ) <= 0.0;
	}
	double t1 = omp_get_wtime();

	/* Lines 7–9: rest lengths from masses (Eq. 11–12). */
	if ( !sim->desiccated )
	{
		status = sere_shrink( model->s.a, model->s.b, model->s.kind, model->s.rest0, model->s.rest, 0, model->s.count,
							  p->m, p->m0, &params->shrink );
		if ( status == SERE_OK )
		{
			status = sere_pbd_set_rest( sim->pbd, model->s.rest );
		}
		if ( status != SERE_OK )
		{
			return status;
		}
		sim->thickness_scale = sere_leaf_thickness_scale( model );
	}
	/* Lighter particles move more: PBD weights by the current inverse mass. */
#pragma omp parallel for simd schedule( static )
	for ( int32_t i = 0; i < p->count; ++i )
	{
		p->inv_m[i] = (float) ( 1.0 / p->m[i] );
	}
	/* Lines 10–13: gravity and prediction. */
	sere_pbd_predict( p->count, p->x, p->y, p->z, p->vx, p->vy, p->vz, p->px, p->py, p->pz, p->inv_m, params->gravity,
					  params->dt );
	double t2 = omp_get_wtime();
	/* Lines 14–16: ĥ stored before projection and collisions. */
	status = sere_collide_measure_h( p->px, p->py, p->pz, model->tri, f, n, sim->h_hat );
	if ( status != SERE_OK )
	{
		return status;
	}
	double t3 = omp_get_wtime();
	/* Lines 17–22: projection of the T, V and L constraints, one colored Gauss–Seidel. */
	sere_pbd_params pbd = params->pbd;
	pbd.dt = params->dt;
	if ( params->soften && sim->water0 > 0.0 )
	{
		double rwc = ( layer_water( p->w, 0, p->count ) ) / sim->water0;
		pbd.stiffness = (float) ( params->pbd.stiffness * ( 0.25 + 0.75 * fmin( 1.0, rwc ) ) );
	}
	sere_pbd_report pbd_report;
	status = project( sim->pbd, p, &pbd, params->pbd_stall, &pbd_report, &stats->pbd_stalled );
	if ( status != SERE_OK )
	{
		return status;
	}
	stats->pbd_iterations = pbd_report.iterations;
	stats->max_strain = pbd_report.max_strain;
	stats->pbd_hit_cap = pbd_report.hit_cap;
	if ( isfinite( params->ground ) )
	{
		const float ground = params->ground;
#pragma omp parallel for simd schedule( static )
		for ( int32_t i = 0; i < p->count; ++i )
		{
			p->pz[i] = p->pz[i] < ground ? ground : p->pz[i];
		}
	}
	/* the start of the frame, before sere_pbd_finish moves it: where each contact's vertex was */
	if ( params->collisions )
	{
		memcpy( sim->x0, p->x, sizeof( float ) * (size_t) n );
		memcpy( sim->y0, p->y, sizeof( float ) * (size_t) n );
		memcpy( sim->z0, p->z, sizeof( float ) * (size_t) n );
	}
	sere_pbd_finish( p->count, p->x, p->y, p->z, p->vx, p->vy, p->vz, p->px, p->py, p->pz, params->dt );
	/* Shrinkage turns into velocity through Δv = Δx/Δt; without damping that momentum
	 * accumulates and a drying leaf drifts away. */
	const float keep = 1.0f - params->damping;
#pragma omp parallel for simd schedule( static )
	for ( int32_t i = 0; i < p->count; ++i )
	{
		p->vx[i] *= keep;
		p->vy[i] *= keep;
		p->vz[i] *= keep;
	}
	double t4 = omp_get_wtime();

	/* Line 23: self-collision of the triangle layer; lines 24–27: Voronoi restore (Eq. 14). */
	if ( params->collisions )
	{
		sere_collide_state state = { p->x, p->y, p->z, p->vx, p->vy, p->vz, p->inv_m, sim->x0, sim->y0, sim->z0 };
		sere_collide_params collide = params->collide;
		collide.dt = params->dt;
		if ( params->scale_thickness )
		{
			collide.thickness *= sim->thickness_scale;
		}
		sere_collide_stats collide_stats;
		status = sere_collide_resolve( sim->collide, sim->bvh, &state, &collide, &collide_stats );
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
		stats->unresolved = collide_stats.unresolved;
		stats->collision_thickness = collide.thickness;
	}
	const float* h = params->restore_measured ? sim->h_hat : model->h;
	status = params->restore_conserving
				 ? sere_collide_restore_voronoi_conserving( p->x, p->y, p->z, p->vx, p->vy, p->vz, p->inv_m, model->tri,
															f, n, h )
				 : sere_collide_restore_voronoi( p->x, p->y, p->z, p->vx, p->vy, p->vz, model->tri, f, n, h );
	if ( status != SERE_OK )
	{
		return status;
	}
	double t5 = omp_get_wtime();

	stats->water_t = layer_water( p->w, 0, n );
	stats->water_v = layer_water( p->w, n, f );
	stats->relative_water = sim->water0 > 0.0 ? ( stats->water_t + stats->water_v ) / sim->water0 : 0.0;
	stats->desiccated = sim->desiccated;
	stats->osmosis_ms = 1e3 * ( t1 - t0 );
	stats->dynamics_ms = 1e3 * ( ( t2 - t1 ) + ( t4 - t3 ) );
	stats->collisions_ms = 1e3 * ( ( t3 - t2 ) + ( t5 - t4 ) );
	stats->total_ms = 1e3 * ( t5 - t0 );
	return SERE_OK;
}

sere_status sere_leaf_shape_initial( sere_leaf_sim* sim, float crease, float curl, const sere_pbd_params* pbd )
{
	sere_model* model = sim->model;
	sere_springs* s = &model->s;
	sere_particles* p = &model->p;
	for ( int32_t k = model->t_springs; k < model->t_springs + model->v_springs; ++k )
	{
		s->rest[k] = s->rest0[k] * ( ( s->kind[k] & SERE_SPRING_VEIN ) ? 1.0f - crease : 1.0f + curl );
	}
	sere_status status = sere_pbd_set_rest( sim->pbd, s->rest );
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
	status = sere_pbd_set_rest( sim->pbd, s->rest );
	if ( status == SERE_OK )
	{
		status = sere_bvh_build( sim->bvh, p->x, p->y, p->z );
	}
	return status;
}
