// The Table 1 leaves, built once per process and shared by every benchmark, so kernels are
// timed on the same models the paper times (maple 13197/51102, plane tree 15069/59550,
// wisteria 12750/50436).
#pragma once

#include "drying/model.h"

#include <vector>

enum sere_bench_leaf
{
	SERE_BENCH_MAPLE = 0,
	SERE_BENCH_PLANE = 1,
	SERE_BENCH_WISTERIA = 2,
};

// A model at rest (never modified by callers: copy what you deform). Aborts the benchmark
// binary with a message if the leaf files cannot be read.
const sere_model* sere_bench_model( sere_bench_leaf leaf );

// The same leaf after `frames` frames of Algorithm 1 with its Table 1 preset (maple-green,
// plane-tree, wisteria): a shrunk, curled and crumpled state for the collision benchmarks. Built
// once per process (the maple's 400 frames take a few seconds) and never modified by callers.
const sere_model* sere_bench_dried_model( sere_bench_leaf leaf, int frames );

// The model's rest lengths with its Voronoi springs shortened by 10%, so that every sweep of a
// projection or descent over them has work to do (bench_pbd.cc, bench_vbd.cc).
std::vector<float> sere_bench_frustrated_rest( const sere_model* model );
