/* sere — one include for every public kernel header. */
#pragma once

#include "base.h"
#include "layers.h"
#include "shape.h"
#include "triangulate.h"
