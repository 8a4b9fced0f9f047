/* sere — one include for every public kernel header (`make header-check` checks that none is
 * missing; the reference twins are in ref/ and not included here). */
#pragma once

/* core: status, memory, plane geometry */
#include "core/array.h"
#include "core/base.h"
#include "core/geometry.h"

/* mesh: plane shapes, triangulation, sampling, B-splines, mesh optimization, subdivision, shape measures */
#include "mesh/bspline.h"
#include "mesh/measure.h"
#include "mesh/meshopt.h"
#include "mesh/sample.h"
#include "mesh/shape.h"
#include "mesh/subdivide.h"
#include "mesh/triangulate.h"

/* solve: the shared solvers other codes plug in: CG, graph coloring, PBD, BVH, collisions */
#include "solve/bvh.h"
#include "solve/cg.h"
#include "solve/collide.h"
#include "solve/color.h"
#include "solve/pbd.h"
#include "solve/vbd.h"

/* drying: Jeong et al.: the double layer, osmosis, shrinkage, the leaf step */
#include "drying/layers.h"
#include "drying/leaf.h"
#include "drying/model.h"
#include "drying/osmosis.h"
#include "drying/shrink.h"

/* season: Tang et al.: mass-spring, Markov chain, L-system tree */
#include "season/lsystem.h"
#include "season/markov.h"
#include "season/massspring.h"

/* wilt: Lu et al.: the venation skeleton */
#include "wilt/skeleton.h"
