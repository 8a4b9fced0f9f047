/* sere harness — what a user looks for in a drying leaf, frame by frame: does it pass through
 * itself, drift with no force on it, leave the ground or turn over. Used by `sere run` for
 * stats.csv and summary.json and by the tests of the drying physics. */
#pragma once

#include "drying/layers.h"
#include "mesh/measure.h"

#ifdef __cplusplus
extern "C"
{
#endif

typedef struct sere_watch_frame
{
	int64_t crossings;	 /* edge–triangle crossings of the triangle layer (kernels/mesh/measure.h) */
	double drift;		 /* area centroid's distance from the fresh one, in fresh leaf lengths */
	double mass_drift;	 /* the centre of mass's own motion summed over the frames (each frame's
						  * displacement taken with that frame's masses, so that water leaving a
						  * particle does not count), in fresh leaf lengths */
	double ground_gap;	 /* lowest particle (either layer) above the ground (NaN without ground) */
	double normal_z;	 /* z of the area-weighted mean unit normal: 1 flat face up, < 0 turned over */
	double tilt_degrees; /* angle between the mean normal and the fresh one */
	double roll_tip;	 /* sere_shape::roll_tip and roll_base of this frame (rad) */
	double roll_base;
} sere_watch_frame;

typedef struct sere_watch sere_watch;

/* Takes the fresh state of model (its current positions) as the reference. Its measures run on
 * `threads` threads (kernels/core/base.h). */
sere_status sere_watch_create( const sere_model* model, double ground, int32_t threads, sere_watch** out );
void sere_watch_destroy( sere_watch* watch );

/* Measures the model's current state; call once after every frame. */
sere_status sere_watch_step( sere_watch* watch, const sere_model* model, sere_watch_frame* out );

/* The fresh leaf's length: its largest extent (the unit of drift). */
double sere_watch_length( const sere_watch* watch );

#ifdef __cplusplus
}
#endif
