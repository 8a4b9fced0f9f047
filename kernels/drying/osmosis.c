/* _GNU_SOURCE: sched_getaffinity for core/internal/team.h. */
#define _GNU_SOURCE

#include "drying/osmosis.h"

#include "core/internal/team.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* The preconditioner's layouts the assembly writes beside a: Jacobi reads the SELL one, SGS and
 * the multigrid the SGS one. A step writes the ones its predecessor used (a layer's stiffness
 * moves slowly) and copies a into the other when its q picks the other preconditioner. */
enum
{
	FILL_SELL = 1,
	FILL_SGS = 2
};

struct sere_osmosis
{
	int32_t threads; /* sere_osmosis_set_threads */
	int32_t first, count;
	sere_csr a;
	sere_sell* sell;		  /* a's SELL layout for the CG, built once (the pattern never changes) and
							   * written by the assembly beside a, through sell->slot */
	sere_sgs* sgs;			  /* a's multicolor SGS layout, built and written the same way */
	sere_amg* amg;			  /* multigrid levels over sgs, built at the first step that needs them */
	int32_t amg_steps;		  /* steps in a row solved with them (SERE_OSMOSIS_AMG_REFRESH): another
							   * preconditioner's step starts the count again, so the multigrid
							   * never resumes with levels older than its own last steps */
	int filled;				  /* the layouts the assembly writes: FILL_SELL, FILL_SGS (the last step's) */
	int csr_current;		  /* a.val holds the last assembly's values (fill_csr): the assembly writes
							   * only the layouts, a's values are copied from one when asked for */
	int32_t* neighbor_spring; /* per CSR entry: the spring it comes from; the diagonal's is
							   * spring_count, whose length and conductance stay 0 */
	int32_t* diagonal;		  /* per row: CSR position of the diagonal */
	const int32_t *sa, *sb;	  /* caller's spring arrays (global indices) */
	int32_t spring_count;
	double *rhs, *c, *edge_sum, *length;
	double* off_sum;	 /* per row, Σ_j a_ij over its off-diagonal entries (assemble's two passes) */
	double* conductance; /* per spring, K_ij of Jeong Eq. 6–8 at this step (both rows read it),
						  * in the conservative mode with its symmetric scale 4/(E_i + E_j) */
	double* last;		 /* the concentration the previous step started from */
	double* last2;		 /* and the one before */
	int history;		 /* how many of last, last2 hold a step (0, 1 or 2) */
	sere_cg_workspace* cg;
};

sere_osmosis_params sere_osmosis_params_default( void )
{
	sere_osmosis_params params = {
		.dt = 0.002,
		.lambda_min = 0.1,
		.lambda_max = 0.1,
		.water_rate = -0.1,
		.mode = SERE_OSMOSIS_PAPER,
		.tolerance = 1e-10,
		.max_iterations = 1000,
		.supply = NULL,
		.supply_count = 0,
		.supply_rate = 0.0,
	};
	return params;
}

void sere_osmosis_destroy( sere_osmosis* o )
{
	if ( o == NULL )
	{
		return;
	}
	sere_free( o->a.row_ptr );
	sere_free( o->a.col );
	sere_free( o->a.val );
	sere_free( o->neighbor_spring );
	sere_free( o->diagonal );
	sere_free( o->rhs );
	sere_free( o->c );
	sere_free( o->last );
	sere_free( o->last2 );
	sere_free( o->edge_sum );
	sere_free( o->off_sum );
	sere_free( o->length );
	sere_free( o->conductance );
	sere_cg_destroy( o->cg );
	sere_sell_destroy( o->sell );
	sere_amg_destroy( o->amg );
	sere_sgs_destroy( o->sgs );
	free( o );
}

sere_status sere_osmosis_create( int32_t first, int32_t count, const int32_t* a, const int32_t* b, int32_t spring_count,
								 sere_osmosis** out )
{
	/* the CSR's nnz, count + 2 · spring_count, and first + count are int32_t */
	if ( out == NULL || first < 0 || count <= 0 || spring_count < 0 || ( spring_count > 0 && ( !a || !b ) ) ||
		 (int64_t) first + count > INT32_MAX || (int64_t) count + 2 * (int64_t) spring_count > INT32_MAX )
	{
		return SERE_ERR_ARGUMENT;
	}
	for ( int32_t s = 0; s < spring_count; ++s )
	{
		if ( a[s] < first || a[s] >= first + count || b[s] < first || b[s] >= first + count || a[s] == b[s] )
		{
			return SERE_ERR_ARGUMENT;
		}
	}
	sere_osmosis* o = calloc( 1, sizeof( *o ) );
	if ( o == NULL )
	{
		return SERE_ERR_MEMORY;
	}
	o->first = first;
	o->count = count;
	o->filled = FILL_SELL | FILL_SGS;
	o->csr_current = 1; /* no step yet: a's values are the zeros written below, as the layouts' */
	o->sa = a;
	o->sb = b;
	o->spring_count = spring_count;
	int32_t nnz = count + 2 * spring_count;
	o->a.rows = count;
	o->a.nnz = nnz;
	o->a.row_ptr = sere_alloc( sizeof( int32_t ) * ( (size_t) count + 1 ) );
	o->a.col = sere_alloc( sizeof( int32_t ) * (size_t) nnz );
	o->a.val = sere_alloc( sizeof( double ) * (size_t) nnz );
	o->neighbor_spring = sere_alloc( sizeof( int32_t ) * (size_t) nnz );
	o->diagonal = sere_alloc( sizeof( int32_t ) * (size_t) count );
	o->rhs = sere_alloc( sizeof( double ) * (size_t) count );
	o->c = sere_alloc( sizeof( double ) * (size_t) count );
	o->last = sere_alloc( sizeof( double ) * (size_t) count );
	o->last2 = sere_alloc( sizeof( double ) * (size_t) count );
	o->edge_sum = sere_alloc( sizeof( double ) * (size_t) count );
	o->off_sum = sere_alloc( sizeof( double ) * (size_t) count );
	o->length = sere_alloc( sizeof( double ) * ( (size_t) spring_count + 1 ) );
	o->conductance = sere_alloc( sizeof( double ) * ( (size_t) spring_count + 1 ) );
	int32_t* fill = malloc( sizeof( int32_t ) * (size_t) count );
	if ( !o->a.row_ptr || !o->a.col || !o->a.val || !o->neighbor_spring || !o->diagonal || !o->rhs || !o->c ||
		 !o->last || !o->last2 || !o->edge_sum || !o->off_sum || !o->length || !o->conductance || !fill ||
		 sere_cg_create( count, &o->cg ) != SERE_OK )
	{
		free( fill );
		sere_osmosis_destroy( o );
		return SERE_ERR_MEMORY;
	}
	o->length[spring_count] = 0.0;
	o->conductance[spring_count] = 0.0;
	memset( o->a.val, 0, sizeof( double ) * (size_t) nnz );
	/* Row i: its springs' other ends in ascending column order with the diagonal in place. */
	for ( int32_t s = 0; s < spring_count; ++s )
	{
		o->a.row_ptr[a[s] - first + 1] += 1;
		o->a.row_ptr[b[s] - first + 1] += 1;
	}
	for ( int32_t i = 0; i < count; ++i )
	{
		o->a.row_ptr[i + 1] += o->a.row_ptr[i] + 1;
		fill[i] = o->a.row_ptr[i];
		o->a.col[fill[i]] = i;
		o->neighbor_spring[fill[i]++] = spring_count;
	}
	for ( int32_t s = 0; s < spring_count; ++s )
	{
		int32_t i = a[s] - first, j = b[s] - first;
		o->a.col[fill[i]] = j;
		o->neighbor_spring[fill[i]++] = s;
		o->a.col[fill[j]] = i;
		o->neighbor_spring[fill[j]++] = s;
	}
	free( fill );
	for ( int32_t i = 0; i < count; ++i )
	{
		/* insertion sort by column: rows hold a handful of entries */
		for ( int32_t k = o->a.row_ptr[i] + 1; k < o->a.row_ptr[i + 1]; ++k )
		{
			int32_t col = o->a.col[k], spring = o->neighbor_spring[k], q = k;
			while ( q > o->a.row_ptr[i] && o->a.col[q - 1] > col )
			{
				o->a.col[q] = o->a.col[q - 1];
				o->neighbor_spring[q] = o->neighbor_spring[q - 1];
				--q;
			}
			o->a.col[q] = col;
			o->neighbor_spring[q] = spring;
		}
		for ( int32_t k = o->a.row_ptr[i]; k < o->a.row_ptr[i + 1]; ++k )
		{
			if ( o->a.col[k] == i )
			{
				o->diagonal[i] = k;
			}
		}
	}
	sere_status status = sere_sell_create( &o->a, SERE_SELL_SIGMA, &o->sell );
	if ( status == SERE_OK )
	{
		status = sere_sgs_create( &o->a, &o->sgs );
	}
	if ( status != SERE_OK )
	{
		sere_osmosis_destroy( o );
		return status;
	}
	*out = o;
	return SERE_OK;
}

/* a's values from the layout the last assembly wrote (each entry's slot there), once a step:
 * for callers who read the matrix and for the switch to the other layout. */
static void fill_csr( sere_osmosis* o )
{
	if ( o->csr_current )
	{
		return;
	}
	const bool sgs = o->filled & FILL_SGS;
	const double* restrict from = sgs ? o->sgs->val : o->sell->val;
	const int32_t* restrict slot = sgs ? o->sgs->slot : o->sell->slot;
	double* restrict val = o->a.val;
	for ( int32_t k = 0; k < o->a.nnz; ++k )
	{
		val[k] = from[slot[k]];
	}
	o->csr_current = 1;
}

const sere_csr* sere_osmosis_matrix( sere_osmosis* o )
{
	fill_csr( o );
	return &o->a;
}

const double* sere_osmosis_rhs( const sere_osmosis* o )
{
	return o->rhs;
}

const double* sere_osmosis_solution( const sere_osmosis* o )
{
	return o->c;
}

sere_status sere_osmosis_set_threads( sere_osmosis* osmosis, int32_t threads )
{
	sere_status status = osmosis == NULL ? SERE_ERR_ARGUMENT : sere_threads_store( &osmosis->threads, threads );
	if ( status == SERE_OK )
	{
		sere_cg_set_threads( osmosis->cg, threads );
		sere_sell_set_threads( osmosis->sell, threads );
		sere_sgs_set_threads( osmosis->sgs, threads );
	}
	return status;
}

/* Per spring at the current positions: its length |l_ij| and its conductance
 * K_ij = λ_ij M_i M_j / (|l_ij| (M_i + M_j)) (Jeong Eq. 6–8 in c, λ_ij by τ̄ as Sec. 4 says), once
 * for both rows it enters (they then hold the same value, bit for bit); then, in the conservative
 * mode, whose rows read their neighbours' E_j, every E_i = Σ_j |l_ij| (Jeong Eq. 3; the paper's
 * mode sums a row's own in the assembly, in the same order) and K_ij scaled by 4/(E_i + E_j),
 * once a spring and in lanes rather than twice in the assembly's rows (E_i + E_j = E_j + E_i, so
 * the same bits). SERE_ERR_GEOMETRY for a spring of zero or non-finite length. */
static sere_status spring_terms( sere_osmosis* o, const float* x, const float* y, const float* z, const float* tau,
								 const double* M, const sere_osmosis_params* params )
{
	const int32_t n = o->count, springs = o->spring_count;
	const double lambda_min = params->lambda_min, lambda_max = params->lambda_max;
	/* locals, so that the stores cannot alias o's fields and the loop vectorizes (gathers) */
	const int32_t* restrict sa = o->sa, * restrict sb = o->sb;
	double* restrict length_out = o->length, * restrict conductance = o->conductance;
	int nonfinite = 0;
#pragma omp parallel for simd num_threads( sere_team_for( o->threads ) ) schedule( static ) reduction( | : nonfinite )
	for ( int32_t s = 0; s < springs; ++s )
	{
		int32_t i = sa[s], j = sb[s];
		double dx = (double) x[j] - x[i], dy = (double) y[j] - y[i], dz = (double) z[j] - z[i];
		double length = sqrt( dx * dx + dy * dy + dz * dz );
		double t = 0.5 * ( (double) tau[i] + (double) tau[j] );
		double lambda = lambda_min * ( 1.0 - t ) + lambda_max * t;
		length_out[s] = length;
		conductance[s] = lambda * M[i] * M[j] / ( length * ( M[i] + M[j] ) );
		nonfinite |= !( length > 0.0 ) || !isfinite( length );
	}
	if ( nonfinite )
	{
		return SERE_ERR_GEOMETRY;
	}
	if ( params->mode != SERE_OSMOSIS_CONSERVATIVE )
	{
		return SERE_OK; /* the paper's rows need only their own E_i: the assembly sums it */
	}
	const int32_t first = o->first;
	double* restrict edge_sum = o->edge_sum;
#pragma omp parallel num_threads( sere_team_for( o->threads ) )
	{
		/* The diagonal's entry adds its spring's length 0: the same bits as leaving it out. */
#pragma omp for schedule( static )
		for ( int32_t i = 0; i < n; ++i )
		{
			double e = 0.0;
			for ( int32_t k = o->a.row_ptr[i]; k < o->a.row_ptr[i + 1]; ++k )
			{
				e += length_out[o->neighbor_spring[k]];
			}
			edge_sum[i] = e;
		}
#pragma omp for simd schedule( static )
		for ( int32_t s = 0; s < springs; ++s )
		{
			conductance[s] *= 4.0 / ( edge_sum[sa[s] - first] + edge_sum[sb[s] - first] ); /* symmetric */
		}
	}
	return SERE_OK;
}

/* The system of Jeong Eq. 8–9 for the new concentrations (made symmetric, as the mode says),
 * its right-hand side and the initial guess; returns the largest Σ_j |a_ij| / a_ii, which
 * picks the preconditioner. */
static double assemble( sere_osmosis* o, const double* M, const double* w, const sere_osmosis_params* params )
{
	const int32_t first = o->first, n = o->count;
	const double dt = params->dt;
	/* Assembly of Jeong Eq. 9, (I − Δt L°) w' = w + r Δt, in c = w/M with row i scaled by E_i/2
	 * (docs/DESIGN.md §6), one row per iteration: every row gathers from its own entries (no
	 * atomics, the same result for any thread count). */
	const double rate_dt = params->water_rate * dt;
	const bool conservative = params->mode == SERE_OSMOSIS_CONSERVATIVE;
	/* The arrays as locals: the stores into the values cannot then alias the index arrays, which
	 * the loop would otherwise load again after every store. */
	const int32_t* restrict row_ptr = o->a.row_ptr;
	const int32_t* restrict spring = o->neighbor_spring, * restrict diagonal = o->diagonal;
	const double* restrict conductance = o->conductance, * restrict length = o->length;
	double* restrict rhs = o->rhs, * restrict c = o->c;
	double* restrict last = o->last, * restrict last2 = o->last2;
	double* restrict edge_sum = o->edge_sum;
	double* sell_val = o->filled & FILL_SELL ? o->sell->val : NULL;
	double* sgs_val = o->filled & FILL_SGS ? o->sgs->val : NULL;
	const int32_t* sell_slot = sell_val != NULL ? o->sell->slot : NULL;
	const int32_t* sgs_slot = sgs_val != NULL ? o->sgs->slot : NULL;
	const int history = o->history;
	double* restrict row_off = o->off_sum;
	double offdiag = 0.0;
#pragma omp parallel num_threads( sere_team_for( o->threads ) )
	{
		/* The entries, row by row in column order: each row's sums are a chain of a handful. */
#pragma omp for schedule( static )
		for ( int32_t i = 0; i < n; ++i )
		{
			double ei = conservative ? edge_sum[i] : 0.0; /* else summed below, as spring_terms would */
			double off_sum = 0.0;
			/* Without a branch: the diagonal's entry reads the spring past the last, whose K and
			 * length are 0, so it adds −0 to the row's sum and +0 to E_i (the same bits as leaving
			 * it out) and its stores are overwritten below. A row's entries are a handful, its
			 * diagonal among them anywhere: a test for it was a branch the predictor missed about
			 * once a row. */
			for ( int32_t k = row_ptr[i]; k < row_ptr[i + 1]; ++k )
			{
				const int32_t s = spring[k];
				if ( !conservative )
				{
					ei += length[s];
				}
				const double value = -dt * conductance[s];
				if ( sell_val != NULL )
				{
					sell_val[sell_slot[k]] = value;
				}
				if ( sgs_val != NULL )
				{
					sgs_val[sgs_slot[k]] = value;
				}
				off_sum += value;
			}
			edge_sum[i] = ei;
			row_off[i] = off_sum;
			const double scale = conservative ? 1.0 : 0.5 * ei;
			const int32_t d = diagonal[i];
			const double aii = scale * M[first + i] - off_sum;
			if ( sell_val != NULL )
			{
				sell_val[sell_slot[d]] = aii;
			}
			if ( sgs_val != NULL )
			{
				sgs_val[sgs_slot[d]] = aii;
			}
		}
		/* What each row needs of its own sums only, in lanes: its two divisions no longer wait
		 * behind the next row's chain. The diagonal a_ii is formed again as above (same bits). */
#pragma omp for simd schedule( static ) reduction( max : offdiag )
		for ( int32_t i = 0; i < n; ++i )
		{
			const int32_t gi = first + i;
			const double mi = M[gi];
			const double scale = conservative ? 1.0 : 0.5 * edge_sum[i];
			const double aii = scale * mi - row_off[i];
			/* Σ_j |a_ij| / a_ii: off-diagonal entries are −Δt K_ij ≤ 0, so −off_sum is their sum */
			const double ratio = -row_off[i] / aii;
			offdiag = ratio > offdiag ? ratio : offdiag;
			rhs[i] = scale * ( w[gi] + rate_dt );
			/* Initial guess: the parabola through the last three concentrations, taken one step
			 * ahead (3 c_n − 3 c_{n−1} + c_{n−2}; the line through two while there are only two).
			 * A drying layer's concentration moves smoothly, so the guess is off by O(Δt³) and CG
			 * has less to remove: on the plane tree's stiff V system (λ = 100) 200 frames take
			 * 18875 iterations instead of 29738 with the line. A concentration is never negative,
			 * so neither is the guess. */
			const double now = w[gi] / mi;
			const double ahead = history == 2	? 3.0 * now - 3.0 * last[i] + last2[i]
								 : history == 1 ? 2.0 * now - last[i]
												: now;
			c[i] = ahead > 0.0 ? ahead : 0.0;
			last2[i] = last[i];
			last[i] = now;
		}
	}
	return offdiag;
}

/* Jeong Eq. 9 solved: SPD after the change of unknown, so preconditioned CG applies, with the
 * preconditioner q = offdiag picks (osmosis.h); its layout takes a's values when the last step
 * wrote the other one. */
static sere_status solve( sere_osmosis* o, double offdiag, const sere_osmosis_params* params,
						  sere_osmosis_report* report, sere_cg_result* result )
{
	report->preconditioner = offdiag > SERE_OSMOSIS_AMG_ABOVE	? SERE_OSMOSIS_AMG
							 : offdiag > SERE_OSMOSIS_SGS_ABOVE ? SERE_OSMOSIS_SGS
																: SERE_OSMOSIS_JACOBI;
	const int needed = report->preconditioner == SERE_OSMOSIS_JACOBI ? FILL_SELL : FILL_SGS;
	sere_status status = SERE_OK;
	if ( !( o->filled & needed ) )
	{
		fill_csr( o );
		status = needed == FILL_SELL ? sere_sell_update( o->sell, &o->a ) : sere_sgs_update( o->sgs, &o->a );
	}
	o->filled = needed;
	const double tol = params->tolerance;
	const int32_t cap = params->max_iterations;
	bool solved = false;
	if ( status == SERE_OK && report->preconditioner == SERE_OSMOSIS_AMG && o->amg == NULL )
	{
		/* The levels cost a dozen iterations to build (BM_AMGSetup): a layer whose guess already
		 * meets the tolerance (the plane tree's triangle layer, every frame) never builds them. */
		status = sere_cg_residual_sgs( o->cg, o->sgs, o->rhs, o->c, &result->residual );
		const bool met = status == SERE_OK && result->residual <= tol;
		solved = status != SERE_OK || met || cap == 0;
		if ( status == SERE_OK && !met )
		{
			status = cap == 0 ? SERE_ERR_NO_CONVERGE : sere_amg_create( &o->a, o->sgs, &o->amg );
		}
	}
	o->amg_steps = report->preconditioner == SERE_OSMOSIS_AMG ? o->amg_steps : 0;
	if ( status == SERE_OK && !solved )
	{
		switch ( report->preconditioner )
		{
			case SERE_OSMOSIS_AMG:
				if ( o->amg_steps++ % SERE_OSMOSIS_AMG_REFRESH == 0 )
				{
					sere_amg_update( o->amg );
				}
				status = sere_cg_solve_amg( o->cg, o->amg, o->rhs, o->c, tol, cap, result );
				break;
			case SERE_OSMOSIS_SGS:
				status = sere_cg_solve_sgs( o->cg, o->sgs, o->rhs, o->c, tol, cap, result );
				break;
			default:
				status = sere_cg_solve( o->cg, o->sell, o->rhs, o->c, tol, cap, result );
		}
	}
	return status;
}

sere_status sere_osmosis_step( sere_osmosis* o, const float* x, const float* y, const float* z, const float* tau,
							   const double* M, double* w, double* m, const sere_osmosis_params* params,
							   sere_osmosis_report* report )
{
	if ( report == NULL )
	{
		return SERE_ERR_ARGUMENT;
	}
	memset( report, 0, sizeof( *report ) );
	if ( o == NULL || params == NULL || x == NULL || y == NULL || z == NULL || tau == NULL || M == NULL || w == NULL ||
		 m == NULL || !( params->dt > 0.0 ) || !( params->lambda_min >= 0.0 ) || !( params->lambda_max >= 0.0 ) ||
		 !isfinite( params->water_rate ) || ( params->supply_count > 0 && params->supply == NULL ) )
	{
		return SERE_ERR_ARGUMENT;
	}
	const int32_t first = o->first, n = o->count;
	const double dt = params->dt;
	double water = 0.0;
	int bad = 0, bad_tau = 0;
	/* in lanes (a fixed order in a build, whatever the threads): the sums are reported and the
	 * first compared with zero, which every order decides alike for water, never negative */
#pragma omp simd reduction( + : water ) reduction( | : bad, bad_tau )
	for ( int32_t i = 0; i < n; ++i )
	{
		water += w[first + i];
		bad |= !( M[first + i] > 0.0 ) || !isfinite( M[first + i] ) || !isfinite( w[first + i] );
		bad_tau |= !isfinite( tau[first + i] );
	}
	report->water_before = water;
	report->water_after = water;
	if ( bad )
	{
		return SERE_ERR_ARGUMENT;
	}
	if ( bad_tau )
	{
		return SERE_ERR_NONFINITE; /* else it would reach the conductances and read as not SPD */
	}
	if ( water <= 0.0 && params->supply_count == 0 )
	{
		report->stopped = 1; /* Sec. 6: a desiccated layer stops flowing */
		return SERE_OK;
	}

	if ( spring_terms( o, x, y, z, tau, M, params ) != SERE_OK )
	{
		return SERE_ERR_GEOMETRY;
	}
	double offdiag = assemble( o, M, w, params );
	o->csr_current = 0;
	for ( int32_t k = 0; k < params->supply_count; ++k )
	{
		int32_t i = params->supply[k] - first;
		if ( i < 0 || i >= n )
		{
			return SERE_ERR_ARGUMENT;
		}
		double scale = params->mode == SERE_OSMOSIS_CONSERVATIVE ? 1.0 : 0.5 * o->edge_sum[i];
		o->rhs[i] += scale * params->supply_rate * dt;
	}

	o->history = o->history < 2 ? o->history + 1 : 2;
	sere_cg_result result = { 0 };
	sere_status status = solve( o, offdiag, params, report, &result );
	report->offdiag = offdiag;
	report->iterations = result.iterations;
	report->residual = result.residual;
	if ( status != SERE_OK && status != SERE_ERR_NO_CONVERGE )
	{
		return status;
	}
	double after = 0.0;
#pragma omp simd reduction( + : after )
	for ( int32_t i = 0; i < n; ++i )
	{
		int32_t gi = first + i;
		double wi = M[gi] * o->c[i];
		w[gi] = wi > 0.0 ? wi : 0.0; /* water is clamped at zero (Sec. 4) */
		m[gi] = M[gi] + w[gi];		 /* Jeong Eq. 10 */
		after += w[gi];
	}
	report->water_after = after;
	return status;
}
