/* Test fixtures of the conjugate gradient tests (test_cg_sgs.c, test_cg_amg.c): osmosis systems
 * assembled on a small double layer, and an independent residual. */
#pragma once

#include "drying/model.h"
#include "drying/osmosis.h"
#include "solve/cg.h"

/* The V layer of a jittered grid double layer after one osmosis step at diffusion λ: its
 * assembled SPD system (owned by *o) and right-hand side (malloc'd). λ = 100 is the plane tree's
 * stiff Voronoi system in miniature, λ = 0.04 the maple's easy one. */
double* sere_test_v_system( sere_model* model, int32_t nx, int32_t ny, double lambda, sere_osmosis** o,
							sere_osmosis_report* report );

/* The V system of sere_test_v_system at λ = 100 with its matrix and the SGS layout built on it. */
typedef struct sere_test_cg_system
{
	sere_model model;
	sere_osmosis* o;
	sere_osmosis_report report;
	double* b;
	const sere_csr* a;
	int32_t n;
	sere_sgs* g;
} sere_test_cg_system;

void sere_test_cg_system_make( sere_test_cg_system* s, int32_t nx, int32_t ny );
void sere_test_cg_system_free( sere_test_cg_system* s );

/* ||b − A x||₂ / ||b||₂ with the CSR product. */
double sere_test_relative_residual( const sere_csr* a, const double* b, const double* x );

/* max_i |x_i − reference_i|, and max_i |reference_i| into *largest. */
double sere_test_worst_difference( const double* x, const double* reference, int32_t n, double* largest );

/* HPCG's symmetry test of an operator B from Bx and By: xᵀBy − yᵀBx into *gap and
 * Σ_i |x_i (By)_i| + |y_i (Bx)_i| (the size rounding is measured against) into *norm; returns
 * xᵀBx. */
double sere_test_symmetry( const double* x, const double* y, const double* bx, const double* by, int32_t n, double* gap,
						   double* norm );
