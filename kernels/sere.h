/* sere — one include for every public kernel header. */
#pragma once

#include "base.h"
#include "bvh.h"
#include "cg.h"
#include "collide.h"
#include "color.h"
#include "layers.h"
#include "leaf.h"
#include "model.h"
#include "osmosis.h"
#include "pbd.h"
#include "sample.h"
#include "shape.h"
#include "shrink.h"
#include "skeleton.h"
#include "subdivide.h"
#include "triangulate.h"
