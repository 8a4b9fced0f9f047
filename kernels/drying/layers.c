#include "drying/layers.h"

#include "core/array.h"

#include <float.h>
#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

sere_layer_params sere_layer_params_default( void )
{
	sere_layer_params params = {
		.h_vein = 0.01,
		.h_surf = 0.01,
		/* Veins carry water more easily: a vein spring counts a fifth of its length in the
		 * shortest-path distance of Sec. 3.3 (Fig. 7 shows the effect of this ratio). */
		.omega_vein = 0.2,
		.omega_surf = 1.0,
		.D = 1.0,
		.m_min = 0.1,
		.m_max = 1.0,
		.mu0 = 0.7,
	};
	return params;
}

sere_status sere_counts_solve( int64_t particles, int64_t springs, int32_t* n, int32_t* b )
{
	if ( n == NULL || b == NULL )
	{
		return SERE_ERR_ARGUMENT;
	}
	/* particles = 3N − B − 2 and springs = 12N − 6B − 12 give 2N − B = (springs + 12) / 6. */
	if ( particles <= 0 || springs <= 0 || ( springs + 12 ) % 6 != 0 )
	{
		return SERE_ERR_COUNTS;
	}
	int64_t two_n_minus_b = ( springs + 12 ) / 6;
	int64_t nn = particles + 2 - two_n_minus_b;
	int64_t bb = 3 * nn - particles - 2;
	if ( nn < 3 || bb < 3 || bb > nn || nn > INT32_MAX / 4 )
	{
		return SERE_ERR_COUNTS;
	}
	*n = (int32_t) nn;
	*b = (int32_t) bb;
	return SERE_OK;
}

static int alloc_particles( sere_particles* p, int32_t count )
{
	p->count = count;
	p->capacity = sere_pad( count );
	size_t fb = sizeof( float ) * (size_t) p->capacity;
	size_t db = sizeof( double ) * (size_t) p->capacity;
	float** floats[] = { &p->x, &p->y, &p->z, &p->vx, &p->vy, &p->vz, &p->px, &p->py, &p->pz, &p->inv_m, &p->tau };
	double** doubles[] = { &p->w, &p->M, &p->m, &p->m0 };
	int ok = 1;
	for ( size_t i = 0; i < sizeof( floats ) / sizeof( floats[0] ); ++i )
	{
		*floats[i] = sere_alloc( fb );
		ok &= *floats[i] != NULL;
	}
	for ( size_t i = 0; i < sizeof( doubles ) / sizeof( doubles[0] ); ++i )
	{
		*doubles[i] = sere_alloc( db );
		ok &= *doubles[i] != NULL;
	}
	return ok;
}

static int alloc_springs( sere_springs* s, int32_t count )
{
	s->count = count;
	s->capacity = sere_pad( count );
	s->a = sere_alloc( sizeof( int32_t ) * (size_t) s->capacity );
	s->b = sere_alloc( sizeof( int32_t ) * (size_t) s->capacity );
	s->rest = sere_alloc( sizeof( float ) * (size_t) s->capacity );
	s->rest0 = sere_alloc( sizeof( float ) * (size_t) s->capacity );
	s->kind = sere_alloc( (size_t) s->capacity );
	return s->a && s->b && s->rest && s->rest0 && s->kind;
}

void sere_model_destroy( sere_model* model )
{
	sere_particles* p = &model->p;
	void* arrays[] = { p->x,		   p->y,		  p->z,		  p->vx,	  p->vy,		   p->vz,
					   p->px,		   p->py,		  p->pz,	  p->inv_m,	  p->tau,		   p->w,
					   p->M,		   p->m,		  p->m0,	  model->s.a, model->s.b,	   model->s.rest,
					   model->s.rest0, model->s.kind, model->tri, model->h,	  model->tri_vein, model->boundary,
					   model->vein,	   model->u,	  model->v,	  model->d };
	sere_free_all( arrays, sizeof( arrays ) / sizeof( arrays[0] ) );
	memset( model, 0, sizeof( *model ) );
}

/* 16-bit Morton interleave: nearby points get nearby indices, so the springs of one color
 * gather from nearby cache lines. */
static uint32_t spread16( uint32_t v )
{
	v &= 0xffff;
	v = ( v | ( v << 8 ) ) & 0x00ff00ff;
	v = ( v | ( v << 4 ) ) & 0x0f0f0f0f;
	v = ( v | ( v << 2 ) ) & 0x33333333;
	v = ( v | ( v << 1 ) ) & 0x55555555;
	return v;
}

static uint64_t morton_key( double x, double y, double x0, double y0, double scale )
{
	uint32_t ix = (uint32_t) fmin( 65535.0, fmax( 0.0, ( x - x0 ) * scale ) );
	uint32_t iy = (uint32_t) fmin( 65535.0, fmax( 0.0, ( y - y0 ) * scale ) );
	return ( spread16( ix ) | ( spread16( iy ) << 1 ) );
}

static uint64_t edge_key( int32_t i, int32_t j )
{
	uint32_t lo = (uint32_t) ( i < j ? i : j );
	uint32_t hi = (uint32_t) ( i < j ? j : i );
	return ( (uint64_t) lo << 32 ) | hi;
}

static int compare_u64( const void* pa, const void* pb )
{
	uint64_t a = *(const uint64_t*) pa;
	uint64_t b = *(const uint64_t*) pb;
	return ( a > b ) - ( a < b );
}

static int has_key( const uint64_t* sorted, int32_t count, uint64_t key )
{
	int32_t lo = 0, hi = count;
	while ( lo < hi )
	{
		int32_t mid = lo + ( hi - lo ) / 2;
		if ( sorted[mid] < key )
		{
			lo = mid + 1;
		}
		else
		{
			hi = mid;
		}
	}
	return lo < count && sorted[lo] == key;
}

static sere_status validate_mesh( const sere_plane_mesh* mesh )
{
	if ( mesh == NULL || mesh->x == NULL || mesh->y == NULL || mesh->tri == NULL || mesh->point_count < 3 ||
		 mesh->triangle_count < 1 || mesh->boundary_count < 3 || mesh->boundary_count > mesh->point_count ||
		 mesh->base < 0 || mesh->base >= mesh->point_count || mesh->vein_segment_count < 0 ||
		 ( mesh->vein_segment_count > 0 && mesh->vein_segments == NULL ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	for ( int32_t i = 0; i < mesh->point_count; ++i )
	{
		if ( !isfinite( mesh->x[i] ) || !isfinite( mesh->y[i] ) )
		{
			return SERE_ERR_NONFINITE;
		}
	}
	for ( int32_t t = 0; t < mesh->triangle_count; ++t )
	{
		const int32_t* v = mesh->tri + 3 * t;
		for ( int k = 0; k < 3; ++k )
		{
			if ( v[k] < 0 || v[k] >= mesh->point_count )
			{
				return SERE_ERR_ARGUMENT;
			}
		}
		double area = ( mesh->x[v[1]] - mesh->x[v[0]] ) * ( mesh->y[v[2]] - mesh->y[v[0]] ) -
					  ( mesh->x[v[2]] - mesh->x[v[0]] ) * ( mesh->y[v[1]] - mesh->y[v[0]] );
		if ( !( area > 0.0 ) )
		{
			return SERE_ERR_GEOMETRY;
		}
	}
	for ( int32_t k = 0; k < 2 * mesh->vein_segment_count; ++k )
	{
		if ( mesh->vein_segments[k] < 0 || mesh->vein_segments[k] >= mesh->point_count )
		{
			return SERE_ERR_ARGUMENT;
		}
	}
	return SERE_OK;
}

/* Triangle particles in Morton order of their plane position; triangles in Morton order of their
 * centroid, so their Voronoi particles follow that order; tri_new holds the renumbered corners. */
static void morton_order( const sere_plane_mesh* mesh, sere_sort_item* order, int32_t* new_of_old, int32_t* tri_new )
{
	const int32_t n = mesh->point_count;
	const int32_t f = mesh->triangle_count;
	double x0 = mesh->x[0], x1 = mesh->x[0], y0 = mesh->y[0], y1 = mesh->y[0];
	for ( int32_t i = 1; i < n; ++i )
	{
		x0 = fmin( x0, mesh->x[i] );
		x1 = fmax( x1, mesh->x[i] );
		y0 = fmin( y0, mesh->y[i] );
		y1 = fmax( y1, mesh->y[i] );
	}
	double scale = 65535.0 / fmax( fmax( x1 - x0, y1 - y0 ), 1e-300 );
	for ( int32_t i = 0; i < n; ++i )
	{
		order[i] = ( sere_sort_item ){ morton_key( mesh->x[i], mesh->y[i], x0, y0, scale ), i, 0 };
	}
	sere_sort_items( order, n );
	for ( int32_t i = 0; i < n; ++i )
	{
		new_of_old[order[i].index] = i;
	}
	for ( int32_t t = 0; t < f; ++t )
	{
		const int32_t* v = mesh->tri + 3 * t;
		double cx = ( mesh->x[v[0]] + mesh->x[v[1]] + mesh->x[v[2]] ) / 3.0;
		double cy = ( mesh->y[v[0]] + mesh->y[v[1]] + mesh->y[v[2]] ) / 3.0;
		order[t] = ( sere_sort_item ){ morton_key( cx, cy, x0, y0, scale ), t, 0 };
	}
	sere_sort_items( order, f );
	for ( int32_t t = 0; t < f; ++t )
	{
		const int32_t* v = mesh->tri + 3 * order[t].index;
		for ( int k = 0; k < 3; ++k )
		{
			tri_new[3 * t + k] = new_of_old[v[k]];
		}
	}
}

/* Each directed half-edge paired with its twin: (undirected edge key, triangle) records sorted,
 * so the two triangles of an interior edge stand side by side. The mesh must be a disk: no edge
 * in three triangles, no holes, no unused points, the boundary its outline (Euler: n + f - e = 1),
 * every boundary edge joining consecutive points of the outline as given (old_of_new: a new
 * index's original one). */
static sere_status pair_half_edges( const sere_plane_mesh* mesh, const int32_t* tri_new, const int32_t* old_of_new,
									sere_sort_item* half, int32_t* unique, int32_t* interior )
{
	const int32_t f = mesh->triangle_count;
	for ( int32_t t = 0; t < f; ++t )
	{
		for ( int k = 0; k < 3; ++k )
		{
			half[3 * t + k] =
				( sere_sort_item ){ edge_key( tri_new[3 * t + k], tri_new[3 * t + ( k + 1 ) % 3] ), t, k };
		}
	}
	sere_sort_items( half, 3 * f );
	int32_t boundary_edges = 0, off_outline = 0;
	*unique = 0;
	*interior = 0;
	for ( int32_t e = 0; e < 3 * f; )
	{
		int32_t run = 1;
		while ( e + run < 3 * f && half[e + run].key == half[e].key )
		{
			++run;
		}
		if ( run > 2 )
		{
			return SERE_ERR_GEOMETRY;
		}
		*unique += 1;
		*interior += run == 2;
		boundary_edges += run == 1;
		if ( run == 1 )
		{
			/* a boundary edge must join consecutive outline points (the first boundary_count, in
			 * order), or the outline flags would mark other points */
			const int32_t* v = tri_new + 3 * half[e].index;
			off_outline += !sere_outline_edge( old_of_new[v[half[e].value]], old_of_new[v[( half[e].value + 1 ) % 3]],
											   mesh->boundary_count );
		}
		e += run;
	}
	return boundary_edges == mesh->boundary_count && off_outline == 0 && mesh->point_count + f - *unique == 1
			   ? SERE_OK
			   : SERE_ERR_GEOMETRY;
}

/* T springs (one per edge), V springs (one per interior edge, joining the Voronoi particles of
 * the two triangles; a vein flag when it crosses a vein T spring, Jeong Fig. 5d) and L springs
 * (corner to Voronoi particle), each kind sorted by its (a, b) key so each color batch reads
 * nearby particles; an entry's value is its spring kind. */
static void spring_entries( sere_model* model, const sere_sort_item* half, const uint64_t* veins, int32_t vein_segments,
							sere_sort_item* entries )
{
	const int32_t n = model->triangle_particles;
	const int32_t f = model->triangle_count;
	int32_t t_count = 0, v_count = 0;
	for ( int32_t e = 0; e < 3 * f; )
	{
		int32_t run = ( e + 1 < 3 * f && half[e + 1].key == half[e].key ) ? 2 : 1;
		uint8_t vein = has_key( veins, vein_segments, half[e].key ) ? SERE_SPRING_VEIN : 0;
		entries[t_count++] = ( sere_sort_item ){ half[e].key, 0, SERE_SPRING_T | vein };
		if ( vein )
		{
			model->tri_vein[half[e].index] = 1;
			if ( run == 2 )
			{
				model->tri_vein[half[e + 1].index] = 1;
			}
		}
		e += run;
	}
	for ( int32_t e = 0; e < 3 * f; )
	{
		int32_t run = ( e + 1 < 3 * f && half[e + 1].key == half[e].key ) ? 2 : 1;
		if ( run == 2 )
		{
			uint8_t vein = has_key( veins, vein_segments, half[e].key ) ? SERE_SPRING_VEIN : 0;
			entries[t_count + v_count++] =
				( sere_sort_item ){ edge_key( n + half[e].index, n + half[e + 1].index ), 0, SERE_SPRING_V | vein };
		}
		e += run;
	}
	int32_t l_first = t_count + v_count;
	for ( int32_t t = 0; t < f; ++t )
	{
		for ( int k = 0; k < 3; ++k )
		{
			entries[l_first + 3 * t + k] =
				( sere_sort_item ){ edge_key( model->tri[3 * t + k], n + t ), 0, SERE_SPRING_L };
		}
	}
	sere_sort_items( entries, t_count );
	sere_sort_items( entries + t_count, v_count );
	sere_sort_items( entries + l_first, 3 * f );
	model->t_springs = t_count;
	model->v_springs = v_count;
	model->l_springs = 3 * f;
}

/* Particles at the mesh points (renumbered) and Voronoi particles at centroid + h·n (Jeong
 * Fig. 5e; the plane mesh is counter-clockwise, so its normal is +z); springs at their rest
 * lengths. SERE_ERR_GEOMETRY for a zero-length spring. */
static sere_status place_particles( sere_model* model, const sere_plane_mesh* mesh, const int32_t* new_of_old,
									const sere_sort_item* entries, const sere_layer_params* params )
{
	const int32_t n = model->triangle_particles;
	const int32_t f = model->triangle_count;
	for ( int32_t i = 0; i < n; ++i )
	{
		int32_t j = new_of_old[i];
		model->p.x[j] = (float) mesh->x[i];
		model->p.y[j] = (float) mesh->y[i];
		model->u[j] = model->p.x[j];
		model->v[j] = model->p.y[j];
		model->boundary[j] = i < mesh->boundary_count;
	}
	for ( int32_t s = 0; s < mesh->vein_segment_count; ++s )
	{
		model->vein[new_of_old[mesh->vein_segments[2 * s]]] = 1;
		model->vein[new_of_old[mesh->vein_segments[2 * s + 1]]] = 1;
	}
	for ( int32_t t = 0; t < f; ++t )
	{
		const int32_t* v = model->tri + 3 * t;
		float h = (float) ( model->tri_vein[t] ? params->h_vein : params->h_surf );
		model->h[t] = h;
		model->p.x[n + t] = ( model->p.x[v[0]] + model->p.x[v[1]] + model->p.x[v[2]] ) / 3.0f;
		model->p.y[n + t] = ( model->p.y[v[0]] + model->p.y[v[1]] + model->p.y[v[2]] ) / 3.0f;
		model->p.z[n + t] = h;
	}
	for ( int32_t i = 0; i < n + f; ++i )
	{
		model->p.px[i] = model->p.x[i];
		model->p.py[i] = model->p.y[i];
		model->p.pz[i] = model->p.z[i];
	}
	int32_t vein_count = 0;
	for ( int32_t s = 0; s < model->s.count; ++s )
	{
		int32_t a = (int32_t) ( entries[s].key >> 32 ), b = (int32_t) ( entries[s].key & 0xffffffffu );
		model->s.a[s] = a;
		model->s.b[s] = b;
		model->s.kind[s] = (uint8_t) entries[s].value;
		vein_count += ( entries[s].value & SERE_SPRING_VEIN ) != 0;
		float dx = model->p.x[b] - model->p.x[a];
		float dy = model->p.y[b] - model->p.y[a];
		float dz = model->p.z[b] - model->p.z[a];
		float length = sqrtf( dx * dx + dy * dy + dz * dz );
		if ( !( length > 0.0f ) )
		{
			return SERE_ERR_GEOMETRY;
		}
		model->s.rest[s] = length;
		model->s.rest0[s] = length;
	}
	model->vein_springs = vein_count;
	return SERE_OK;
}

static bool alloc_model_arrays( sere_model* model, int32_t n, int32_t f, int32_t spring_count )
{
	if ( !alloc_particles( &model->p, n + f ) || !alloc_springs( &model->s, spring_count ) )
	{
		return false;
	}
	model->tri = sere_alloc( sizeof( int32_t ) * 3 * (size_t) f );
	model->h = sere_alloc( sizeof( float ) * (size_t) sere_pad( f ) );
	model->tri_vein = sere_alloc( (size_t) sere_pad( f ) );
	model->boundary = sere_alloc( (size_t) sere_pad( n ) );
	model->vein = sere_alloc( (size_t) sere_pad( n ) );
	model->u = sere_alloc( sizeof( float ) * (size_t) sere_pad( n ) );
	model->v = sere_alloc( sizeof( float ) * (size_t) sere_pad( n ) );
	model->d = sere_alloc( sizeof( double ) * (size_t) model->p.capacity );
	return model->tri && model->h && model->tri_vein && model->boundary && model->vein && model->u && model->v &&
		   model->d;
}

sere_status sere_model_from_triangles( const sere_plane_mesh* mesh, const sere_layer_params* params, sere_model* model )
{
	if ( model == NULL )
	{
		return SERE_ERR_ARGUMENT;
	}
	memset( model, 0, sizeof( *model ) );
	sere_status status = validate_mesh( mesh );
	if ( status != SERE_OK || params == NULL )
	{
		return status != SERE_OK ? status : SERE_ERR_ARGUMENT;
	}
	const int32_t n = mesh->point_count;
	const int32_t f = mesh->triangle_count;
	sere_sort_item* order = malloc( sizeof( sere_sort_item ) * (size_t) ( n > f ? n : f ) );
	int32_t* new_of_old = malloc( sizeof( int32_t ) * (size_t) n );
	int32_t* old_of_new = malloc( sizeof( int32_t ) * (size_t) n );
	int32_t* tri_new = malloc( sizeof( int32_t ) * 3 * (size_t) f );
	sere_sort_item* half = malloc( sizeof( sere_sort_item ) * 3 * (size_t) f );
	uint64_t* veins =
		malloc( sizeof( uint64_t ) * (size_t) ( mesh->vein_segment_count > 0 ? mesh->vein_segment_count : 1 ) );
	sere_sort_item* entries = NULL;
	if ( !order || !new_of_old || !old_of_new || !tri_new || !half || !veins )
	{
		status = SERE_ERR_MEMORY;
		goto done;
	}
	morton_order( mesh, order, new_of_old, tri_new );
	for ( int32_t s = 0; s < mesh->vein_segment_count; ++s )
	{
		veins[s] = edge_key( new_of_old[mesh->vein_segments[2 * s]], new_of_old[mesh->vein_segments[2 * s + 1]] );
	}
	qsort( veins, (size_t) mesh->vein_segment_count, sizeof( uint64_t ), compare_u64 );

	int32_t unique, interior;
	for ( int32_t i = 0; i < n; ++i )
	{
		old_of_new[new_of_old[i]] = i;
	}
	status = pair_half_edges( mesh, tri_new, old_of_new, half, &unique, &interior );
	if ( status != SERE_OK )
	{
		goto done;
	}
	const int32_t spring_count = unique + interior + 3 * f;
	entries = malloc( sizeof( sere_sort_item ) * (size_t) spring_count );
	if ( entries == NULL || !alloc_model_arrays( model, n, f, spring_count ) )
	{
		status = SERE_ERR_MEMORY;
		goto done;
	}
	model->triangle_particles = n;
	model->triangle_count = f;
	model->boundary_count = mesh->boundary_count;
	model->base = new_of_old[mesh->base];
	memcpy( model->tri, tri_new, sizeof( int32_t ) * 3 * (size_t) f );
	spring_entries( model, half, veins, mesh->vein_segment_count, entries );
	status = place_particles( model, mesh, new_of_old, entries, params );
	if ( status == SERE_OK )
	{
		status = sere_model_assign_masses( model, params );
	}

done:
	free( order );
	free( new_of_old );
	free( old_of_new );
	free( tri_new );
	free( half );
	free( veins );
	free( entries );
	if ( status != SERE_OK )
	{
		sere_model_destroy( model );
	}
	return status;
}

/* Binary min-heap of (distance, particle) for Dijkstra. */
typedef struct heap_item
{
	double d;
	int32_t i;
} heap_item;

static void heap_push( heap_item* heap, int32_t* size, heap_item item )
{
	int32_t k = ( *size )++;
	while ( k > 0 )
	{
		int32_t parent = ( k - 1 ) / 2;
		if ( heap[parent].d < item.d || ( heap[parent].d == item.d && heap[parent].i <= item.i ) )
		{
			break;
		}
		heap[k] = heap[parent];
		k = parent;
	}
	heap[k] = item;
}

static heap_item heap_pop( heap_item* heap, int32_t* size )
{
	heap_item top = heap[0];
	heap_item last = heap[--( *size )];
	int32_t k = 0;
	for ( ;; )
	{
		int32_t child = 2 * k + 1;
		if ( child >= *size )
		{
			break;
		}
		if ( child + 1 < *size && ( heap[child + 1].d < heap[child].d ||
									( heap[child + 1].d == heap[child].d && heap[child + 1].i < heap[child].i ) ) )
		{
			child += 1;
		}
		if ( last.d < heap[child].d || ( last.d == heap[child].d && last.i <= heap[child].i ) )
		{
			break;
		}
		heap[k] = heap[child];
		k = child;
	}
	heap[k] = last;
	return top;
}

sere_status sere_model_assign_masses( sere_model* model, const sere_layer_params* params )
{
	/* written so that NaN fails every test; m_min > 0, as a particle of mass 0 would take an
	 * infinite inverse mass (0 is the pin) */
	if ( model == NULL || params == NULL || !( params->m_min > 0.0 ) || !( params->m_max >= params->m_min ) ||
		 !( params->m_max <= DBL_MAX ) || !( params->mu0 >= 0.0 && params->mu0 < 1.0 ) ||
		 !( params->D > 0.0 && params->D <= DBL_MAX ) ||
		 !( params->omega_vein > 0.0 && params->omega_vein <= DBL_MAX ) ||
		 !( params->omega_surf > 0.0 && params->omega_surf <= DBL_MAX ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	const int32_t n = model->triangle_particles;
	const int32_t t_springs = model->t_springs;
	/* CSR adjacency of the triangle layer over T springs. */
	int32_t* offsets = calloc( (size_t) n + 1, sizeof( int32_t ) );
	int32_t* adjacent = malloc( sizeof( int32_t ) * 2 * (size_t) t_springs );
	double* weight = malloc( sizeof( double ) * 2 * (size_t) t_springs );
	int32_t* fill = malloc( sizeof( int32_t ) * (size_t) n );
	heap_item* heap = malloc( sizeof( heap_item ) * ( 2 * (size_t) t_springs + 1 ) );
	uint8_t* settled = calloc( (size_t) n, 1 );
	if ( !offsets || !adjacent || !weight || !fill || !heap || !settled )
	{
		free( offsets ), free( adjacent ), free( weight ), free( fill ), free( heap ), free( settled );
		return SERE_ERR_MEMORY;
	}
	for ( int32_t s = 0; s < t_springs; ++s )
	{
		offsets[model->s.a[s] + 1] += 1;
		offsets[model->s.b[s] + 1] += 1;
	}
	for ( int32_t i = 0; i < n; ++i )
	{
		offsets[i + 1] += offsets[i];
		fill[i] = offsets[i];
	}
	for ( int32_t s = 0; s < t_springs; ++s )
	{
		int32_t a = model->s.a[s], b = model->s.b[s];
		double omega = ( model->s.kind[s] & SERE_SPRING_VEIN ) ? params->omega_vein : params->omega_surf;
		double w = omega * model->s.rest0[s];
		adjacent[fill[a]] = b;
		weight[fill[a]++] = w;
		adjacent[fill[b]] = a;
		weight[fill[b]++] = w;
	}

	/* Shortest weighted distances from the base (Sec. 3.3). */
	double* d = model->d;
	for ( int32_t i = 0; i < n; ++i )
	{
		d[i] = INFINITY;
	}
	int32_t size = 0;
	d[model->base] = 0.0;
	heap_push( heap, &size, ( heap_item ){ 0.0, model->base } );
	while ( size > 0 )
	{
		heap_item top = heap_pop( heap, &size );
		if ( settled[top.i] )
		{
			continue;
		}
		settled[top.i] = 1;
		for ( int32_t k = offsets[top.i]; k < offsets[top.i + 1]; ++k )
		{
			int32_t j = adjacent[k];
			double candidate = top.d + weight[k];
			if ( candidate < d[j] )
			{
				d[j] = candidate;
				heap_push( heap, &size, ( heap_item ){ candidate, j } );
			}
		}
	}
	free( offsets ), free( adjacent ), free( weight ), free( fill ), free( heap ), free( settled );

	double d_max = 0.0;
	for ( int32_t i = 0; i < n; ++i )
	{
		if ( !isfinite( d[i] ) )
		{
			return SERE_ERR_GEOMETRY; /* a particle the base cannot reach */
		}
		d_max = fmax( d_max, d[i] );
	}
	sere_particles* p = &model->p;
	for ( int32_t i = 0; i < n; ++i )
	{
		double tau = d_max > 0.0 ? pow( 1.0 - d[i] / d_max, params->D ) : 1.0; /* Jeong Eq. 1 */
		p->tau[i] = (float) tau;
		p->m0[i] = params->m_min * ( 1.0 - tau ) + params->m_max * tau; /* Jeong Eq. 2 */
	}
	/* A Voronoi particle takes the mean of its triangle's three (Sec. 4). */
	for ( int32_t t = 0; t < model->triangle_count; ++t )
	{
		const int32_t* v = model->tri + 3 * t;
		int32_t i = n + t;
		d[i] = ( d[v[0]] + d[v[1]] + d[v[2]] ) / 3.0;
		p->tau[i] = ( p->tau[v[0]] + p->tau[v[1]] + p->tau[v[2]] ) / 3.0f;
		p->m0[i] = ( p->m0[v[0]] + p->m0[v[1]] + p->m0[v[2]] ) / 3.0;
	}
	for ( int32_t i = 0; i < p->count; ++i )
	{
		p->m[i] = p->m0[i];
		p->w[i] = params->mu0 * p->m0[i];
		p->M[i] = p->m0[i] - p->w[i];
		p->inv_m[i] = (float) ( 1.0 / p->m0[i] );
	}
	return SERE_OK;
}

void sere_model_triangle_normal( const sere_model* model, int32_t t, float normal[3] )
{
	const int32_t* v = model->tri + 3 * t;
	const float* x = model->p.x;
	const float* y = model->p.y;
	const float* z = model->p.z;
	float ex = x[v[1]] - x[v[0]], ey = y[v[1]] - y[v[0]], ez = z[v[1]] - z[v[0]];
	float fx = x[v[2]] - x[v[0]], fy = y[v[2]] - y[v[0]], fz = z[v[2]] - z[v[0]];
	float nx = ey * fz - ez * fy, ny = ez * fx - ex * fz, nz = ex * fy - ey * fx;
	float length = sqrtf( nx * nx + ny * ny + nz * nz );
	float inv = length > 0.0f ? 1.0f / length : 0.0f;
	normal[0] = nx * inv;
	normal[1] = ny * inv;
	normal[2] = nz * inv;
}

void sere_model_mirror_z( sere_model* model )
{
	sere_particles* p = &model->p;
	float low = INFINITY, high = -INFINITY;
	for ( int32_t i = 0; i < p->count; ++i )
	{
		low = p->z[i] < low ? p->z[i] : low;
		high = p->z[i] > high ? p->z[i] : high;
	}
	/* z -> low + high - z: turned over in place, the lowest point still at low */
	for ( int32_t i = 0; i < p->count; ++i )
	{
		p->z[i] = ( low + high ) - p->z[i];
		p->pz[i] = ( low + high ) - p->pz[i];
		p->vz[i] = -p->vz[i];
	}
	for ( int32_t t = 0; t < model->triangle_count; ++t )
	{
		model->h[t] = -model->h[t];
	}
}

void sere_model_rest_on( sere_model* model, float ground )
{
	sere_particles* p = &model->p;
	if ( !isfinite( ground ) || p->count == 0 )
	{
		return;
	}
	float low = INFINITY;
	for ( int32_t i = 0; i < p->count; ++i )
	{
		low = p->z[i] < low ? p->z[i] : low;
	}
	const float shift = ground - low;
	for ( int32_t i = 0; i < p->count; ++i )
	{
		p->z[i] += shift;
		p->pz[i] += shift;
	}
}
