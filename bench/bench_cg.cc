// Osmotic flow systems of the Table 1 maple (T and V layers) and plane tree (V): our SpMV (CSR and
// SELL-C-sigma) and PCG (Jacobi, SGS, aggregation multigrid) at 1 and 2 threads beside Eigen 3.4's
// ConjugateGradient with a diagonal preconditioner and hypre's BoomerAMG PCG, same matrix, same
// tolerance (relative residual 1e-8), in one binary.
#include "drying/osmosis.h"
#include "fixture.h"
#include "solve/cg.h"

#include <Eigen/IterativeLinearSolvers>
#include <Eigen/Sparse>
#include <HYPRE.h>
#include <HYPRE_krylov.h>
#include <HYPRE_parcsr_ls.h>
#include <benchmark/benchmark.h>
#include <mpi.h>
#include <omp.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <vector>

namespace
{
struct system_t
{
	sere_osmosis* osmosis = nullptr;
	std::vector<double> b;
};

// Systems by index: 0 = the maple's T layer, 1 = its V layer (lambda 0.04, maple-green), 2 = the
// plane tree's V layer (lambda 100, plane-tree: the stiff Voronoi system). Each is assembled once
// from its leaf at rest.
system_t& leaf_system( int index )
{
	static system_t systems[3];
	system_t& s = systems[index];
	if ( s.osmosis != nullptr )
	{
		return s;
	}
	const int layer = index == 0 ? 0 : 1;
	const sere_model* m = sere_bench_model( index == 2 ? SERE_BENCH_PLANE : SERE_BENCH_MAPLE );
	int32_t first = layer == 0 ? 0 : m->triangle_particles;
	int32_t count = layer == 0 ? m->triangle_particles : m->triangle_count;
	int32_t s0 = layer == 0 ? 0 : m->t_springs;
	int32_t sc = layer == 0 ? m->t_springs : m->v_springs;
	sere_osmosis_create( first, count, m->s.a + s0, m->s.b + s0, sc, &s.osmosis );
	std::vector<double> w( m->p.w, m->p.w + m->p.count ), mass( m->p.m, m->p.m + m->p.count );
	sere_osmosis_params params = sere_osmosis_params_default();
	params.lambda_min = params.lambda_max = index == 2 ? 100.0 : 0.04;
	sere_osmosis_report report;
	sere_osmosis_step( s.osmosis, m->p.x, m->p.y, m->p.z, m->p.tau, m->p.M, w.data(), mass.data(), &params, &report );
	const double* rhs = sere_osmosis_rhs( s.osmosis );
	s.b.assign( rhs, rhs + count );
	return s;
}

// max over rows of sum_j |a_ij| / a_ii (j != i): Gershgorin's bound on the Jacobi-scaled
// spectrum, [1 - q, 1 + q]; the osmosis picks its preconditioner by it.
double offdiag_ratio( const sere_csr* a )
{
	double q = 0.0;
	for ( int32_t i = 0; i < a->rows; ++i )
	{
		double off = 0.0, d = 0.0;
		for ( int32_t k = a->row_ptr[i]; k < a->row_ptr[i + 1]; ++k )
		{
			( a->col[k] == i ? d : off ) += std::fabs( a->val[k] );
		}
		q = std::max( q, off / d );
	}
	return q;
}

system_t& maple_system( int layer )
{
	return leaf_system( layer );
}

// Two flops per stored entry and product, as a rate over the benchmark's iterations.
benchmark::Counter spmv_gflops( const benchmark::State& state, const sere_csr* a )
{
	return benchmark::Counter( 2.0 * a->nnz * state.iterations() * 1e-9, benchmark::Counter::kIsRate );
}

void BM_SpMV( benchmark::State& state )
{
	omp_set_num_threads( static_cast<int>( state.range( 1 ) ) );
	system_t& s = maple_system( static_cast<int>( state.range( 0 ) ) );
	const sere_csr* a = sere_osmosis_matrix( s.osmosis );
	std::vector<double> x( a->rows, 1.0 ), y( a->rows );
	for ( auto _ : state )
	{
		sere_csr_spmv( a, x.data(), y.data(), static_cast<int32_t>( state.range( 1 ) ) );
		benchmark::DoNotOptimize( y.data() );
	}
	state.counters["GFLOP/s"] = spmv_gflops( state, a );
	state.counters["GB/s"] = benchmark::Counter( ( 12.0 * a->nnz + 20.0 * a->rows ) * state.iterations() * 1e-9,
												 benchmark::Counter::kIsRate );
}

// Args: layer, threads, sigma (the sorting window).
void BM_SellSpMV( benchmark::State& state )
{
	omp_set_num_threads( static_cast<int>( state.range( 1 ) ) );
	system_t& s = maple_system( static_cast<int>( state.range( 0 ) ) );
	const sere_csr* a = sere_osmosis_matrix( s.osmosis );
	sere_sell* sell;
	if ( sere_sell_create( a, static_cast<int32_t>( state.range( 2 ) ), &sell ) != SERE_OK )
	{
		state.SkipWithError( "sere_sell_create failed" );
		return;
	}
	std::vector<double> x( a->rows, 1.0 ), y( a->rows );
	for ( auto _ : state )
	{
		sere_sell_spmv( sell, x.data(), y.data() );
		benchmark::DoNotOptimize( y.data() );
	}
	state.counters["GFLOP/s"] = spmv_gflops( state, a );
	state.counters["padding"] = static_cast<double>( sell->chunk_ptr[sell->chunks] - a->nnz ) / a->nnz;
	sere_sell_destroy( sell );
}

// Copying new values into a kept SELL layout (the osmosis instead writes them while assembling).
void BM_SellUpdate( benchmark::State& state )
{
	omp_set_num_threads( static_cast<int>( state.range( 1 ) ) );
	system_t& s = maple_system( static_cast<int>( state.range( 0 ) ) );
	const sere_csr* a = sere_osmosis_matrix( s.osmosis );
	sere_sell* sell;
	sere_sell_create( a, SERE_SELL_SIGMA, &sell );
	for ( auto _ : state )
	{
		sere_sell_update( sell, a );
		benchmark::DoNotOptimize( sell->val );
	}
	sere_sell_destroy( sell );
}

// One solve from x = 0 to relative residual 1e-8. Args: system (0 maple T, 1 maple V, 2 plane
// tree V), threads, preconditioner (0 Jacobi on the SELL layout the osmosis keeps, 1 multicolor
// SGS in Eisenstat's form). GFLOP/s counts 2 flops per matrix entry per product (SGS: its two
// sweeps read each entry once) and the vector updates; GB/s the matrix (12 bytes an entry) and
// the vectors each iteration streams.
void BM_PCG( benchmark::State& state )
{
	omp_set_num_threads( static_cast<int>( state.range( 1 ) ) );
	system_t& s = leaf_system( static_cast<int>( state.range( 0 ) ) );
	const bool sgs_on = state.range( 2 ) == 1;
	const sere_csr* a = sere_osmosis_matrix( s.osmosis );
	sere_sell* sell = nullptr;
	sere_sgs* sgs = nullptr;
	if ( ( sgs_on ? sere_sgs_create( a, &sgs ) : sere_sell_create( a, SERE_SELL_SIGMA, &sell ) ) != SERE_OK )
	{
		state.SkipWithError( "layout failed" );
		return;
	}
	sere_cg_workspace* w;
	sere_cg_create( a->rows, &w );
	std::vector<double> x( a->rows );
	sere_cg_result result{};
	for ( auto _ : state )
	{
		std::fill( x.begin(), x.end(), 0.0 );
		if ( sgs_on )
		{
			sere_cg_solve_sgs( w, sgs, s.b.data(), x.data(), 1e-8, 10000, &result );
		}
		else
		{
			sere_cg_solve( w, sell, s.b.data(), x.data(), 1e-8, 10000, &result );
		}
		benchmark::DoNotOptimize( x.data() );
	}
	const double per_iteration_flops = 2.0 * a->nnz + 14.0 * a->rows;
	const double per_iteration_bytes = 12.0 * a->nnz + 8.0 * ( sgs_on ? 16 : 11 ) * a->rows;
	state.counters["iterations"] = result.iterations;
	state.counters["residual"] = result.residual;
	state.counters["rows"] = a->rows;
	state.counters["colors"] = sgs_on ? sgs->colors : 0;
	state.counters["offdiag"] = offdiag_ratio( a );
	const int32_t stored =
		sgs_on ? sgs->upper_ptr[sgs->chunks] + sgs->chunks * SERE_SELL_C : sell->chunk_ptr[sell->chunks];
	state.counters["padding"] = static_cast<double>( stored - a->nnz ) / a->nnz;
	state.counters["GFLOP/s"] = benchmark::Counter( per_iteration_flops * result.iterations * state.iterations() * 1e-9,
													benchmark::Counter::kIsRate );
	state.counters["GB/s"] = benchmark::Counter( per_iteration_bytes * result.iterations * state.iterations() * 1e-9,
												 benchmark::Counter::kIsRate );
	sere_cg_destroy( w );
	sere_sell_destroy( sell );
	sere_sgs_destroy( sgs );
}

// The multigrid over a system's matrix, its levels refreshed once, and a workspace, for BM_AMG and
// BM_AMGFloor; ok is false when a part could not be made.
struct amg_solver
{
	sere_sgs* sgs = nullptr;
	sere_amg* amg = nullptr;
	sere_cg_workspace* w = nullptr;
	bool ok;
	explicit amg_solver( const sere_csr* a )
		: ok( sere_sgs_create( a, &sgs ) == SERE_OK && sere_amg_create( a, sgs, &amg ) == SERE_OK &&
			  sere_cg_create( a->rows, &w ) == SERE_OK && sere_amg_update( amg ) == SERE_OK )
	{
	}
	~amg_solver()
	{
		sere_cg_destroy( w );
		sere_amg_destroy( amg );
		sere_sgs_destroy( sgs );
	}
};

// Our aggregation multigrid PCG (sere_cg_solve_amg) on the same systems, from x = 0 to relative
// residual 1e-8, beside hypre's BoomerAMG PCG below. Args: system, threads, refresh (0: the coarse
// levels refreshed once, outside the timing: the solve alone; 1: refreshed for every solve, as the
// osmosis does every frame; their aggregates are built once either way, as the osmosis builds
// them once). Counters: the levels and the rows of the first coarse level.
void BM_AMG( benchmark::State& state )
{
	omp_set_num_threads( static_cast<int>( state.range( 1 ) ) );
	system_t& s = leaf_system( static_cast<int>( state.range( 0 ) ) );
	const bool refresh = state.range( 2 ) == 1;
	const sere_csr* a = sere_osmosis_matrix( s.osmosis );
	amg_solver m( a );
	if ( !m.ok )
	{
		state.SkipWithError( "levels failed" );
		return;
	}
	std::vector<double> x( a->rows );
	sere_cg_result result{};
	for ( auto _ : state )
	{
		std::fill( x.begin(), x.end(), 0.0 );
		if ( refresh )
		{
			sere_amg_update( m.amg );
		}
		sere_cg_solve_amg( m.w, m.amg, s.b.data(), x.data(), 1e-8, 10000, &result );
		benchmark::DoNotOptimize( x.data() );
	}
	state.counters["iterations"] = result.iterations;
	state.counters["residual"] = result.residual;
	state.counters["rows"] = a->rows;
	state.counters["levels"] = sere_amg_levels( m.amg );
	state.counters["coarse_rows"] = sere_amg_rows( m.amg, 1 );
}

// Building the multigrid levels from the pattern (sere_amg_create: aggregates, the coarse
// patterns, their SGS layouts and the Galerkin sums' order), which the osmosis does once, at the
// first step whose layer takes the multigrid; beside BM_HypreAMG's setup:1, which sets BoomerAMG
// up for every solve. Args: system.
void BM_AMGSetup( benchmark::State& state )
{
	system_t& s = leaf_system( static_cast<int>( state.range( 0 ) ) );
	const sere_csr* a = sere_osmosis_matrix( s.osmosis );
	sere_sgs* sgs = nullptr;
	if ( sere_sgs_create( a, &sgs ) != SERE_OK )
	{
		state.SkipWithError( "layout failed" );
		return;
	}
	int32_t levels = 0;
	for ( auto _ : state )
	{
		sere_amg* amg = nullptr;
		if ( sere_amg_create( a, sgs, &amg ) != SERE_OK )
		{
			state.SkipWithError( "levels failed" );
			break;
		}
		levels = sere_amg_levels( amg );
		sere_amg_destroy( amg );
	}
	sere_sgs_destroy( sgs );
	state.counters["rows"] = a->rows;
	state.counters["levels"] = levels;
	state.counters["rows/s"] =
		benchmark::Counter( static_cast<double>( a->rows ) * state.iterations(), benchmark::Counter::kIsRate );
}

// The multigrid PCG's floor (sere_cg_touch_amg): the same passes over every level's arrays with
// adds only, as many iterations as BM_AMG's solve of the same system takes. Args: system, threads.
void BM_AMGFloor( benchmark::State& state )
{
	omp_set_num_threads( static_cast<int>( state.range( 1 ) ) );
	system_t& s = leaf_system( static_cast<int>( state.range( 0 ) ) );
	const sere_csr* a = sere_osmosis_matrix( s.osmosis );
	amg_solver m( a );
	if ( !m.ok )
	{
		state.SkipWithError( "levels failed" );
		return;
	}
	std::vector<double> x( a->rows, 0.0 );
	sere_cg_result result{};
	sere_cg_solve_amg( m.w, m.amg, s.b.data(), x.data(), 1e-8, 10000, &result );
	for ( auto _ : state )
	{
		sere_cg_touch_amg( m.w, m.amg, result.iterations );
		benchmark::ClobberMemory();
	}
	state.counters["iterations"] = result.iterations;
}

// The SGS PCG's floor (sere_cg_touch_sgs): each step's update pass and its backward and forward
// sweeps over the same arrays at the same barriers, adds only, as many steps as BM_PCG's SGS solve
// of the same system takes (its start, restarts and true residuals are not in it). Args: system,
// threads.
void BM_SGSFloor( benchmark::State& state )
{
	omp_set_num_threads( static_cast<int>( state.range( 1 ) ) );
	system_t& s = leaf_system( static_cast<int>( state.range( 0 ) ) );
	const sere_csr* a = sere_osmosis_matrix( s.osmosis );
	sere_sgs* sgs = nullptr;
	sere_cg_workspace* w = nullptr;
	if ( sere_sgs_create( a, &sgs ) != SERE_OK || sere_cg_create( a->rows, &w ) != SERE_OK )
	{
		sere_sgs_destroy( sgs );
		state.SkipWithError( "layout failed" );
		return;
	}
	std::vector<double> x( a->rows, 0.0 );
	sere_cg_result result{};
	sere_cg_solve_sgs( w, sgs, s.b.data(), x.data(), 1e-8, 10000, &result );
	for ( auto _ : state )
	{
		sere_cg_touch_sgs( w, sgs, result.iterations );
		benchmark::ClobberMemory();
	}
	state.counters["iterations"] = result.iterations;
	sere_cg_destroy( w );
	sere_sgs_destroy( sgs );
}

// The barrier the solve's passes meet at (kernels/core/internal/team.h, sere_spin_barrier): a
// count and a generation, spun on. Written again here in C++ atomics because that header's C11
// _Atomic types do not compile as C++17; the floor must not pay libgomp's barrier, a system call
// each, where the solve does not.
struct spin_barrier
{
	alignas( 64 ) std::atomic<unsigned> arrived{ 0 };
	alignas( 64 ) std::atomic<unsigned> generation{ 0 };
	void wait( int threads )
	{
		if ( threads == 1 )
		{
			return;
		}
		unsigned g = generation.load( std::memory_order_relaxed );
		if ( arrived.fetch_add( 1, std::memory_order_acq_rel ) == static_cast<unsigned>( threads ) - 1 )
		{
			arrived.store( 0, std::memory_order_relaxed );
			generation.store( g + 1, std::memory_order_release );
			return;
		}
		while ( generation.load( std::memory_order_acquire ) == g )
		{
		}
	}
};

// The Jacobi PCG's floor: the memory traffic of our solve's iterations with no multiplications
// and no sums. Per iteration, as sere_cg_solve's round: one pass over the positions reading the
// seven vectors it reads (u, p, w, s, x, r, D^-1) and writing the five it writes, then the product
// over the SELL layout (values, columns, u gathered four lanes at a time as the kernel gathers
// them) storing w; each combination is one add where the solve does its multiply-adds, and a
// spin barrier after each pass as in the solve. It runs as many iterations as our solve of the
// same system takes. Args: system, threads.
void BM_PCGFloor( benchmark::State& state )
{
	const int threads = static_cast<int>( state.range( 1 ) );
	system_t& s = leaf_system( static_cast<int>( state.range( 0 ) ) );
	const sere_csr* a = sere_osmosis_matrix( s.osmosis );
	sere_sell* sell = nullptr;
	sere_cg_workspace* w = nullptr;
	if ( sere_sell_create( a, SERE_SELL_SIGMA, &sell ) != SERE_OK || sere_cg_create( a->rows, &w ) != SERE_OK )
	{
		state.SkipWithError( "layout failed" );
		return;
	}
	std::vector<double> x0( a->rows, 0.0 );
	sere_cg_result result{};
	sere_cg_solve( w, sell, s.b.data(), x0.data(), 1e-8, 10000, &result );
	typedef double quad __attribute__( ( vector_size( 4 * sizeof( double ) ) ) );
	const int32_t np = sell->chunks * SERE_SELL_C;
	// aligned as the workspace's vectors (sere_alloc): the product stores whole 4-lane vectors
	double* vectors[7];
	for ( double*& v : vectors )
	{
		v = static_cast<double*>( sere_alloc( sizeof( double ) * static_cast<size_t>( np ) ) );
		std::fill( v, v + np, 1.0 );
	}
	double* __restrict u = vectors[0], * __restrict p = vectors[1], * __restrict wv = vectors[2];
	double* __restrict sv = vectors[3], * __restrict xv = vectors[4], * __restrict r = vectors[5];
	const double* __restrict d = vectors[6];
	const int32_t* col = sell->local_col;
	const double* val = sell->val;
	const int32_t chunks = sell->chunks;
	spin_barrier barrier;
	for ( auto _ : state )
	{
#pragma omp parallel num_threads( threads )
		for ( int32_t it = 0; it < result.iterations; ++it )
		{
#pragma omp for simd schedule( static ) nowait
			for ( int32_t i = 0; i < np; ++i )
			{
				p[i] = u[i] + p[i];
				sv[i] = wv[i] + sv[i];
				xv[i] = xv[i] + p[i];
				r[i] = r[i] + sv[i];
				u[i] = d[i] + r[i];
			}
			barrier.wait( omp_get_num_threads() );
#pragma omp for schedule( static ) nowait
			for ( int32_t c = 0; c < chunks; ++c )
			{
				quad lo = { 0.0 }, hi = { 0.0 };
				for ( int32_t q = sell->chunk_ptr[c]; q < sell->chunk_ptr[c + 1]; q += SERE_SELL_C )
				{
					const int32_t* k = col + q;
					lo += *reinterpret_cast<const quad*>( val + q ) + quad{ u[k[0]], u[k[1]], u[k[2]], u[k[3]] };
					hi += *reinterpret_cast<const quad*>( val + q + 4 ) + quad{ u[k[4]], u[k[5]], u[k[6]], u[k[7]] };
				}
				*reinterpret_cast<quad*>( wv + c * SERE_SELL_C ) = lo;
				*reinterpret_cast<quad*>( wv + c * SERE_SELL_C + 4 ) = hi;
			}
			barrier.wait( omp_get_num_threads() );
		}
		benchmark::DoNotOptimize( u );
		benchmark::ClobberMemory();
	}
	state.counters["iterations"] = result.iterations;
	state.counters["GB/s"] = benchmark::Counter( ( 12.0 * sell->chunk_ptr[chunks] + 8.0 * 13 * np ) *
													 result.iterations * state.iterations() * 1e-9,
												 benchmark::Counter::kIsRate );
	for ( double* v : vectors )
	{
		sere_free( v );
	}
	sere_cg_destroy( w );
	sere_sell_destroy( sell );
}

void BM_EigenCG( benchmark::State& state )
{
	Eigen::setNbThreads( static_cast<int>( state.range( 1 ) ) );
	system_t& s = leaf_system( static_cast<int>( state.range( 0 ) ) );
	const sere_csr* a = sere_osmosis_matrix( s.osmosis );
	std::vector<Eigen::Triplet<double>> entries;
	for ( int32_t i = 0; i < a->rows; ++i )
	{
		for ( int32_t k = a->row_ptr[i]; k < a->row_ptr[i + 1]; ++k )
		{
			entries.emplace_back( i, a->col[k], a->val[k] );
		}
	}
	Eigen::SparseMatrix<double, Eigen::RowMajor> matrix( a->rows, a->rows );
	matrix.setFromTriplets( entries.begin(), entries.end() );
	Eigen::ConjugateGradient<Eigen::SparseMatrix<double, Eigen::RowMajor>, Eigen::Lower | Eigen::Upper,
							 Eigen::DiagonalPreconditioner<double>>
		cg;
	cg.setTolerance( 1e-8 );
	cg.compute( matrix );
	Eigen::Map<const Eigen::VectorXd> b( s.b.data(), a->rows );
	Eigen::VectorXd x;
	for ( auto _ : state )
	{
		x = cg.solve( b );
		benchmark::DoNotOptimize( x.data() );
	}
	state.counters["iterations"] = static_cast<double>( cg.iterations() );
	state.counters["rows"] = a->rows;
}

// hypre (Debian's build: MPI, no OpenMP, so one thread) in one process: MPI_COMM_SELF, MPI and
// hypre started once and finalized at exit.
void hypre_start()
{
	static bool started = false;
	if ( started )
	{
		return;
	}
	int initialized = 0;
	MPI_Initialized( &initialized );
	if ( !initialized )
	{
		MPI_Init( nullptr, nullptr );
	}
	HYPRE_Init();
	std::atexit( [] {
		HYPRE_Finalize();
		MPI_Finalize();
	} );
	started = true;
}

// hypre's PCG with one BoomerAMG V-cycle as the preconditioner (HMIS coarsening, ext+i
// interpolation, hybrid symmetric Gauss-Seidel smoothing: hypre's recommended defaults for 2D/3D
// diffusion), same system and tolerance (two-norm relative residual 1e-8). Args: system, setup
// (0: the AMG hierarchy is built once, outside the timing: the solve alone; 1: built for every
// solve, as a simulation whose matrix changes every frame would have to).
void BM_HypreAMG( benchmark::State& state )
{
	hypre_start();
	system_t& s = leaf_system( static_cast<int>( state.range( 0 ) ) );
	const bool setup_each = state.range( 1 ) == 1;
	const sere_csr* a = sere_osmosis_matrix( s.osmosis );
	const HYPRE_Int n = a->rows;
	HYPRE_IJMatrix ij;
	HYPRE_IJMatrixCreate( MPI_COMM_SELF, 0, n - 1, 0, n - 1, &ij );
	HYPRE_IJMatrixSetObjectType( ij, HYPRE_PARCSR );
	HYPRE_IJMatrixInitialize( ij );
	for ( HYPRE_Int i = 0; i < n; ++i )
	{
		HYPRE_Int count = a->row_ptr[i + 1] - a->row_ptr[i];
		std::vector<HYPRE_Int> cols( a->col + a->row_ptr[i], a->col + a->row_ptr[i + 1] );
		HYPRE_IJMatrixSetValues( ij, 1, &count, &i, cols.data(), a->val + a->row_ptr[i] );
	}
	HYPRE_IJMatrixAssemble( ij );
	HYPRE_ParCSRMatrix matrix;
	HYPRE_IJMatrixGetObject( ij, reinterpret_cast<void**>( &matrix ) );
	std::vector<HYPRE_Int> rows( static_cast<size_t>( n ) );
	for ( HYPRE_Int i = 0; i < n; ++i )
	{
		rows[static_cast<size_t>( i )] = i;
	}
	std::vector<double> zero( static_cast<size_t>( n ), 0.0 );
	HYPRE_IJVector ijb, ijx;
	HYPRE_ParVector b, x;
	for ( HYPRE_IJVector* v : { &ijb, &ijx } )
	{
		HYPRE_IJVectorCreate( MPI_COMM_SELF, 0, n - 1, v );
		HYPRE_IJVectorSetObjectType( *v, HYPRE_PARCSR );
		HYPRE_IJVectorInitialize( *v );
		HYPRE_IJVectorSetValues( *v, n, rows.data(), v == &ijb ? s.b.data() : zero.data() );
		HYPRE_IJVectorAssemble( *v );
	}
	HYPRE_IJVectorGetObject( ijb, reinterpret_cast<void**>( &b ) );
	HYPRE_IJVectorGetObject( ijx, reinterpret_cast<void**>( &x ) );
	HYPRE_Solver pcg, amg;
	HYPRE_ParCSRPCGCreate( MPI_COMM_SELF, &pcg );
	HYPRE_PCGSetTol( pcg, 1e-8 );
	HYPRE_PCGSetMaxIter( pcg, 10000 );
	HYPRE_PCGSetTwoNorm( pcg, 1 );
	HYPRE_PCGSetPrintLevel( pcg, 0 );
	HYPRE_BoomerAMGCreate( &amg );
	HYPRE_BoomerAMGSetPrintLevel( amg, 0 );
	HYPRE_BoomerAMGSetCoarsenType( amg, 10 );
	HYPRE_BoomerAMGSetInterpType( amg, 6 );
	HYPRE_BoomerAMGSetRelaxType( amg, 6 );
	HYPRE_BoomerAMGSetNumSweeps( amg, 1 );
	HYPRE_BoomerAMGSetStrongThreshold( amg, 0.25 );
	HYPRE_BoomerAMGSetTol( amg, 0.0 );
	HYPRE_BoomerAMGSetMaxIter( amg, 1 );
	HYPRE_PCGSetPrecond( pcg, reinterpret_cast<HYPRE_PtrToSolverFcn>( HYPRE_BoomerAMGSolve ),
						 reinterpret_cast<HYPRE_PtrToSolverFcn>( HYPRE_BoomerAMGSetup ), amg );
	HYPRE_ParCSRPCGSetup( pcg, matrix, b, x );
	for ( auto _ : state )
	{
		HYPRE_ParVectorSetConstantValues( x, 0.0 );
		if ( setup_each )
		{
			HYPRE_BoomerAMGSetup( amg, matrix, b, x );
		}
		HYPRE_ParCSRPCGSolve( pcg, matrix, b, x );
		benchmark::DoNotOptimize( x );
	}
	HYPRE_Int iterations = 0;
	double residual = 0.0;
	HYPRE_PCGGetNumIterations( pcg, &iterations );
	HYPRE_PCGGetFinalRelativeResidualNorm( pcg, &residual );
	state.counters["iterations"] = iterations;
	state.counters["residual"] = residual;
	state.counters["rows"] = n;
	HYPRE_BoomerAMGDestroy( amg );
	HYPRE_ParCSRPCGDestroy( pcg );
	HYPRE_IJVectorDestroy( ijb );
	HYPRE_IJVectorDestroy( ijx );
	HYPRE_IJMatrixDestroy( ij );
}

// One osmosis step of a layer as a drying frame runs it (Jeong Eq. 6-9: the springs' lengths and
// conductances, the assembly into CSR and the preconditioner's layout, the warm-started PCG), from
// the leaf at rest each time: the water and masses are restored before every step (two copies of
// the layer's doubles, a few µs), so every step solves the same system. With cap 1 the CG
// stops after its first true residual: what remains is the assembly's share. Args: system (as
// leaf_system), threads, cap (0 the preset's 1000 iterations, 1 none).
void BM_OsmosisStep( benchmark::State& state )
{
	const int index = static_cast<int>( state.range( 0 ) );
	omp_set_num_threads( static_cast<int>( state.range( 1 ) ) );
	const sere_model* m = sere_bench_model( index == 2 ? SERE_BENCH_PLANE : SERE_BENCH_MAPLE );
	const bool triangle = index == 0;
	const int32_t first = triangle ? 0 : m->triangle_particles;
	const int32_t count = triangle ? m->triangle_particles : m->triangle_count;
	const int32_t s0 = triangle ? 0 : m->t_springs, springs = triangle ? m->t_springs : m->v_springs;
	sere_osmosis* o = nullptr;
	if ( sere_osmosis_create( first, count, m->s.a + s0, m->s.b + s0, springs, &o ) != SERE_OK )
	{
		state.SkipWithError( "osmosis failed" );
		return;
	}
	const std::vector<double> w0( m->p.w, m->p.w + m->p.count ), mass0( m->p.m, m->p.m + m->p.count );
	std::vector<double> w( w0 ), mass( mass0 );
	sere_osmosis_params params = sere_osmosis_params_default();
	params.lambda_min = params.lambda_max = index == 2 ? 100.0 : 0.04;
	params.max_iterations = state.range( 2 ) == 1 ? 0 : params.max_iterations;
	sere_osmosis_report report{};
	for ( auto _ : state )
	{
		std::copy( w0.begin() + first, w0.begin() + first + count, w.begin() + first );
		std::copy( mass0.begin() + first, mass0.begin() + first + count, mass.begin() + first );
		sere_status status =
			sere_osmosis_step( o, m->p.x, m->p.y, m->p.z, m->p.tau, m->p.M, w.data(), mass.data(), &params, &report );
		if ( status != SERE_OK && status != SERE_ERR_NO_CONVERGE )
		{
			state.SkipWithError( "osmosis step failed" );
			break;
		}
		benchmark::DoNotOptimize( w.data() );
	}
	state.counters["rows"] = count;
	state.counters["springs"] = springs;
	state.counters["iterations"] = report.iterations;
	state.counters["springs/s"] =
		benchmark::Counter( static_cast<double>( springs ) * state.iterations(), benchmark::Counter::kIsRate );
	sere_osmosis_destroy( o );
}
} // namespace

// Args: layer (0 = T, 1 = V), threads.
BENCHMARK( BM_SpMV )->ArgNames( { "layer", "threads" } )->ArgsProduct( { { 0, 1 }, { 1, 2 } } )->UseRealTime();
BENCHMARK( BM_SellSpMV )
	->ArgNames( { "layer", "threads", "sigma" } )
	->ArgsProduct( { { 0, 1 }, { 1, 2 }, { 8, 64, 512 } } )
	->UseRealTime();
BENCHMARK( BM_SellUpdate )->ArgNames( { "layer", "threads" } )->ArgsProduct( { { 0, 1 }, { 1, 2 } } )->UseRealTime();
BENCHMARK( BM_PCG )
	->ArgNames( { "system", "threads", "sgs" } )
	->ArgsProduct( { { 0, 1, 2 }, { 1, 2 }, { 0, 1 } } )
	->UseRealTime()
	->Unit( benchmark::kMicrosecond );
BENCHMARK( BM_AMG )
	->ArgNames( { "system", "threads", "refresh" } )
	->ArgsProduct( { { 0, 1, 2 }, { 1, 2 }, { 0, 1 } } )
	->UseRealTime()
	->Unit( benchmark::kMicrosecond );
BENCHMARK( BM_AMGSetup )->ArgName( "system" )->DenseRange( 0, 2 )->UseRealTime()->Unit( benchmark::kMicrosecond );
BENCHMARK( BM_SGSFloor )
	->ArgNames( { "system", "threads" } )
	->ArgsProduct( { { 0, 1, 2 }, { 1, 2 } } )
	->UseRealTime()
	->Unit( benchmark::kMicrosecond );
BENCHMARK( BM_AMGFloor )
	->ArgNames( { "system", "threads" } )
	->ArgsProduct( { { 0, 1, 2 }, { 1, 2 } } )
	->UseRealTime()
	->Unit( benchmark::kMicrosecond );
BENCHMARK( BM_PCGFloor )
	->ArgNames( { "system", "threads" } )
	->ArgsProduct( { { 0, 1, 2 }, { 1, 2 } } )
	->UseRealTime()
	->Unit( benchmark::kMicrosecond );
BENCHMARK( BM_EigenCG )
	->ArgNames( { "system", "threads" } )
	->ArgsProduct( { { 0, 1, 2 }, { 1, 2 } } )
	->UseRealTime()
	->Unit( benchmark::kMicrosecond );
BENCHMARK( BM_OsmosisStep )
	->ArgNames( { "system", "threads", "cap" } )
	->ArgsProduct( { { 0, 1, 2 }, { 1, 2 }, { 0, 1 } } )
	->UseRealTime()
	->Unit( benchmark::kMicrosecond );
BENCHMARK( BM_HypreAMG )
	->ArgNames( { "system", "setup" } )
	->ArgsProduct( { { 0, 1, 2 }, { 0, 1 } } )
	->UseRealTime()
	->Unit( benchmark::kMicrosecond );
