// Osmotic flow systems of the Table 1 maple (T and V layers): our SpMV and Jacobi PCG at 1 and
// 2 threads beside Eigen 3.4's ConjugateGradient with a diagonal preconditioner, same matrix,
// same tolerance (relative residual 1e-8), in one binary.
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

void BM_PCG( benchmark::State& state )
{
	omp_set_num_threads( static_cast<int>( state.range( 1 ) ) );
	system_t& s = maple_system( static_cast<int>( state.range( 0 ) ) );
	const sere_csr* a = sere_osmosis_matrix( s.osmosis );
	sere_cg_workspace* w;
	sere_cg_create( a->rows, &w );
	std::vector<double> x( a->rows );
	sere_cg_result result{};
	for ( auto _ : state )
	{
		std::fill( x.begin(), x.end(), 0.0 );
		sere_cg_solve( w, a, s.b.data(), x.data(), 1e-8, 10000, &result );
		benchmark::DoNotOptimize( x.data() );
	}
	state.counters["iterations"] = result.iterations;
	state.counters["rows"] = a->rows;
	sere_cg_destroy( w );
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
