#include "skeleton_leaf.h"

#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

double skeleton_half_width( double x, double length, double width, double lobes )
{
	double xi = x / length;
	if ( xi <= 0.0 || xi >= 1.0 )
	{
		return 0.0;
	}
	double h = 0.5 * width * sqrt( xi ) * ( 1.0 - xi ) / ( sqrt( 1.0 / 3.0 ) * ( 2.0 / 3.0 ) );
	return h * ( 1.0 - lobes * fabs( sin( 3.0 * 3.14159265358979323846 * xi ) ) );
}

void skeleton_grid_leaf( sere_tri_mesh* mesh, double length, double width, double lobes, int32_t nx, int32_t ny )
{
	int32_t nv = ( nx + 1 ) * ( ny + 1 );
	int32_t* tri = malloc( 6 * (size_t) nx * ny * sizeof( int32_t ) );
	int32_t* used = calloc( (size_t) nv, sizeof( int32_t ) );
	int32_t count = 0;
	for ( int32_t j = 0; j < ny; ++j )
	{
		for ( int32_t i = 0; i < nx; ++i )
		{
			int32_t a = j * ( nx + 1 ) + i, b = a + 1, c = a + nx + 1, d = c + 1;
			int32_t cand[2][3] = { { a, b, d }, { a, d, c } };
			for ( int k = 0; k < 2; ++k )
			{
				double cx = 0.0, cy = 0.0;
				for ( int q = 0; q < 3; ++q )
				{
					cx += ( cand[k][q] % ( nx + 1 ) ) * length / nx / 3.0;
					cy += ( -0.5 * width + ( cand[k][q] / ( nx + 1 ) ) * width / ny ) / 3.0;
				}
				if ( lobes < 0.0 || fabs( cy ) < skeleton_half_width( cx, length, width, lobes ) )
				{
					memcpy( tri + 3 * count++, cand[k], 3 * sizeof( int32_t ) );
				}
			}
		}
	}
	int32_t vertices = 0;
	for ( int32_t k = 0; k < 3 * count; ++k )
	{
		used[tri[k]] = 1;
	}
	for ( int32_t v = 0; v < nv; ++v )
	{
		used[v] = used[v] ? vertices++ : -1;
	}
	cr_assert_eq( sere_tri_mesh_create( mesh, vertices, count ), SERE_OK );
	for ( int32_t v = 0; v < nv; ++v )
	{
		if ( used[v] >= 0 )
		{
			int32_t i = v % ( nx + 1 ), j = v / ( nx + 1 );
			mesh->x[used[v]] = (float) ( i * length / nx );
			mesh->y[used[v]] = (float) ( -0.5 * width + j * width / ny );
			mesh->u[used[v]] = (float) i / nx;
			mesh->v[used[v]] = (float) j / ny;
		}
	}
	for ( int32_t k = 0; k < 3 * count; ++k )
	{
		mesh->tri[k] = used[tri[k]];
	}
	free( tri );
	free( used );
}

void skeleton_parametric_leaf( double* l, double* r, double* m, sere_leaf_skeleton* leaf )
{
	cr_assert_eq( sere_leaf_skeleton_generate( 10.0, 6.0, 9, l, r, m ), SERE_OK );
	*leaf = ( sere_leaf_skeleton ){ 9, 9, 9, l, r, m };
}

void skeleton_generated( sere_skeleton* s, const sere_venation_params* params )
{
	double l[18], r[18], m[18];
	sere_leaf_skeleton leaf;
	skeleton_parametric_leaf( l, r, m, &leaf );
	sere_venation_params p = params != NULL ? *params : sere_venation_params_default();
	sere_skeleton_check check;
	cr_assert_eq( sere_skeleton_generate( &leaf, &p, s, &check ), SERE_OK, "%s",
				  sere_skeleton_problem_text( check.problem ) );
}
