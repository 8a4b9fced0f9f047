/* sere — a tree from an L-system (seed 002, Sec. 6: "we adopt the L-system method to produce the
 * trunks and branches of the tree ... the leaves grown on branches are modeled as triangular
 * meshes"), after Prusinkiewicz and Lindenmayer's bracketed 3D L-systems.
 *
 * Rewriting: every symbol with a rule is replaced by the rule's string, all at once, iterations
 * times (deterministic, context-free). Interpretation by a turtle with a position and a frame
 * (heading H, left L, up U), starting at the origin with H = +z (up the trunk), L = +y, U = H × L = −x:
 *   F   draw a branch segment of the current length and radius, move to its end
 *   f   move forward without drawing
 *   + − turn left / right about U by the angle
 *   & ^ pitch down / up about L by the angle
 *   / \ roll right / left about H by the roll angle (the divergence angle, 137.5° by default)
 *   |   turn around (180° about U)
 *   [ ] push / pop the turtle state
 *   !   the next segments are thinner and shorter: radius × radius_ratio, length × length_ratio
 *   L   a leaf at the turtle's position
 * Other symbols (A, B, ...) only rewrite. Every turn is perturbed by a random angle in
 * [−jitter, jitter] drawn from a counter-based generator keyed by (seed, the symbol's index in
 * the final string), so the same parameters always give the same tree.
 *
 * Leaves: a leaf's blade points along the turtle's heading projected onto the horizontal plane
 * and turned by a random angle, tilted down by `leaf_droop`, with its face normal as close to
 * +z (the sky) as that allows: how leaves of a broadleaf tree present themselves to the light. */
#pragma once

#include "core/base.h"

#ifdef __cplusplus
extern "C"
{
#endif

typedef struct sere_lsystem_rule
{
	char symbol;
	const char* replacement;
} sere_lsystem_rule;

typedef struct sere_lsystem_params
{
	const char* axiom;
	const sere_lsystem_rule* rules;
	int32_t rule_count;
	int32_t iterations;
	int64_t max_symbols; /* SERE_ERR_CAPACITY when the rewritten string would be longer */
	double angle_deg;	 /* + − & ^ */
	double roll_deg;	 /* / \ */
	double length;		 /* of the first segments */
	double radius;
	double length_ratio; /* ! */
	double radius_ratio;
	double jitter_deg;
	double leaf_droop_deg; /* tilt of every blade below the horizontal */
	uint64_t seed;
} sere_lsystem_params;

/* A maple-like tree: a trunk that branches in threes with a 137.5° roll between whorls, leaves
 * at every twig, 6 iterations (1092 leaves on 1095 segments). */
sere_lsystem_params sere_lsystem_params_default( void );

/* The tree in SoA. Segment k runs from (x0, y0, z0)[k] with radius r0[k] to (x1, y1, z1)[k]
 * with r1[k]. Leaf k sits at (leaf_x, leaf_y, leaf_z)[k]; its blade direction (unit) is
 * leaf_dir{x,y,z}[k] and its face normal (unit, orthogonal to the direction) leaf_n{x,y,z}[k]. */
typedef struct sere_tree
{
	int32_t segment_count;
	float *x0, *y0, *z0, *r0;
	float *x1, *y1, *z1, *r1;
	int32_t leaf_count;
	float *leaf_x, *leaf_y, *leaf_z;
	float *leaf_dirx, *leaf_diry, *leaf_dirz;
	float *leaf_nx, *leaf_ny, *leaf_nz;
	int32_t max_depth; /* deepest bracket nesting met */
} sere_tree;

/* The rewritten string (NUL-terminated, *length symbols), the caller's to free.
 * SERE_ERR_ARGUMENT for a missing axiom, a negative iteration count, a rule without a string or
 * two rules for one symbol; SERE_ERR_CAPACITY past max_symbols. */
sere_status sere_lsystem_rewrite( const sere_lsystem_params* params, char** out, int64_t* length );

/* Rewrites and interprets. Errors as sere_lsystem_rewrite, plus SERE_ERR_ARGUMENT for a
 * non-positive or non-finite length or radius, ratios outside (0, 1], and SERE_ERR_GEOMETRY for
 * unbalanced brackets. On failure nothing is left to free. */
sere_status sere_tree_grow( const sere_lsystem_params* params, sere_tree* tree );
void sere_tree_destroy( sere_tree* tree );

#ifdef __cplusplus
}
#endif
