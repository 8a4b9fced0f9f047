/* sere — reference twin of massspring.c: a plain scalar transcription of Sec. 4 of seed 002.
 * Each step: F_i = m_i g plus every spring's force added to its two ends in spring order;
 * a = F/m, v ← (1 − drag)(v + a Δt) (Tang Eq. 1); Tang Eq. 2 applied spring by spring in index order,
 * sweep after sweep, until no spring is off the band by more than the tolerance; x ← x + v Δt.
 * Same law, parameters and report as sere_massspring_step; used by tests and benches. */
#pragma once

#include "season/massspring.h"

#ifdef __cplusplus
extern "C"
{
#endif

/* topology: the springs (e.g. sere_massspring_get_topology of the optimized kernel, so both sweep the
 * structural springs in the same order); fx, fy, fz: particles->count floats of scratch. */
sere_status sere_massspring_ref_step( const sere_massspring_topology* topology, sere_massspring_particles* particles,
									  const sere_massspring_params* params, float* fx, float* fy, float* fz,
									  sere_massspring_report* report );

#ifdef __cplusplus
}
#endif
