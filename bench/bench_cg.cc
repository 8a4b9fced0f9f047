// Osmotic flow systems of the Table 1 maple (T and V layers): our SpMV (CSR and SELL-C-sigma) and
// Jacobi PCG at 1 and 2 threads beside Eigen 3.4's ConjugateGradient with a diagonal
// preconditioner, same matrix, same tolerance (relative residual 1e-8), in one binary.
#include "cg.h"
#include "fixture.h"
#include "osmosis.h"

#include <Eigen/IterativeLinearSolvers>
#include <Eigen/Sparse>
#include <benchmark/benchmark.h>
#include <omp.h>

#include <vector>

namespace
{
struct system_t
{
	sere_osmosis* osmosis = nullptr;
	std::vector<double> b;
};

// Layer 0 = T, 1 = V; assembled once from the maple at rest with the maple-green lambda.
system_t& maple_system( int layer )
{
	static system_t systems[2];
	system_t& s = systems[layer];
	if ( s.osmosis != nullptr )
	{
		return s;
	}
	const sere_model* m = sere_bench_model( SERE_BENCH_MAPLE );
	int32_t first = layer == 0 ? 0 : m->triangle_particles;
	int32_t count = layer == 0 ? m->triangle_particles : m->triangle_count;
	int32_t s0 = layer == 0 ? 0 : m->t_springs;
	int32_t sc = layer == 0 ? m->t_springs : m->v_springs;
	sere_osmosis_create( first, count, m->s.a + s0, m->s.b + s0, sc, &s.osmosis );
	std::vector<double> w( m->p.w, m->p.w + m->p.count ), mass( m->p.m, m->p.m + m->p.count );
	sere_osmosis_params params = sere_osmosis_params_default();
	params.lambda_min = params.lambda_max = 0.04;
	sere_osmosis_report report;
	sere_osmosis_step( s.osmosis, m->p.x, m->p.y, m->p.z, m->p.tau, m->p.M, w.data(), mass.data(), &params, &report );
	const double* rhs = sere_osmosis_rhs( s.osmosis );
	s.b.assign( rhs, rhs + count );
	return s;
}

void BM_SpMV( benchmark::State& state )
{
	omp_set_num_threads( static_cast<int>( state.range( 1 ) ) );
	system_t& s = maple_system( static_cast<int>( state.range( 0 ) ) );
	const sere_csr* a = sere_osmosis_matrix( s.osmosis );
	std::vector<double> x( a->rows, 1.0 ), y( a->rows );
	for ( auto _ : state )
	{
		sere_csr_spmv( a, x.data(), y.data() );
		benchmark::DoNotOptimize( y.data() );
	}
	state.counters["GFLOP/s"] =
		benchmark::Counter( 2.0 * a->nnz * state.iterations() * 1e-9, benchmark::Counter::kIsRate );
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
	state.counters["GFLOP/s"] =
		benchmark::Counter( 2.0 * a->nnz * state.iterations() * 1e-9, benchmark::Counter::kIsRate );
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

// One solve on the SELL layout the osmosis step keeps and fills while assembling.
void BM_PCG( benchmark::State& state )
{
	omp_set_num_threads( static_cast<int>( state.range( 1 ) ) );
	system_t& s = maple_system( static_cast<int>( state.range( 0 ) ) );
	const sere_csr* a = sere_osmosis_matrix( s.osmosis );
	sere_sell* sell;
	sere_sell_create( a, SERE_SELL_SIGMA, &sell );
	sere_cg_workspace* w;
	sere_cg_create( a->rows, &w );
	std::vector<double> x( a->rows );
	sere_cg_result result{};
	for ( auto _ : state )
	{
		std::fill( x.begin(), x.end(), 0.0 );
		sere_cg_solve( w, sell, s.b.data(), x.data(), 1e-8, 10000, &result );
		benchmark::DoNotOptimize( x.data() );
	}
	state.counters["iterations"] = result.iterations;
	state.counters["residual"] = result.residual;
	state.counters["rows"] = a->rows;
	sere_cg_destroy( w );
	sere_sell_destroy( sell );
}

void BM_EigenCG( benchmark::State& state )
{
	Eigen::setNbThreads( static_cast<int>( state.range( 1 ) ) );
	system_t& s = maple_system( static_cast<int>( state.range( 0 ) ) );
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
} // namespace

// Args: layer (0 = T, 1 = V), threads.
BENCHMARK( BM_SpMV )->ArgNames( { "layer", "threads" } )->ArgsProduct( { { 0, 1 }, { 1, 2 } } )->UseRealTime();
BENCHMARK( BM_SellSpMV )
	->ArgNames( { "layer", "threads", "sigma" } )
	->ArgsProduct( { { 0, 1 }, { 1, 2 }, { 8, 64, 512 } } )
	->UseRealTime();
BENCHMARK( BM_SellUpdate )->ArgNames( { "layer", "threads" } )->ArgsProduct( { { 0, 1 }, { 1, 2 } } )->UseRealTime();
BENCHMARK( BM_PCG )
	->ArgNames( { "layer", "threads" } )
	->ArgsProduct( { { 0, 1 }, { 1, 2 } } )
	->UseRealTime()
	->Unit( benchmark::kMicrosecond );
BENCHMARK( BM_EigenCG )
	->ArgNames( { "layer", "threads" } )
	->ArgsProduct( { { 0, 1 }, { 1, 2 } } )
	->UseRealTime()
	->Unit( benchmark::kMicrosecond );
