/* sere harness — the machine facts every result carries: CPU model, SIMD path, OpenMP threads
 * and their binding, the sere version and commit, the compiler. A timing without them cannot
 * be compared with another one. */
#pragma once

#include <stdio.h>

#ifdef __cplusplus
extern "C"
{
#endif

#define SERE_MACHINE_MAX_THREADS 256

typedef struct sere_machine
{
	char cpu[256];						   /* /proc/cpuinfo "model name", else hwloc's CPUModel, else "unknown" */
	const char* simd;					   /* sere_simd_path() */
	int threads;						   /* the OpenMP thread count the caller runs with (as given) */
	int cores;							   /* physical cores as hwloc counts them (sere_topo_cores()) */
	int bound;							   /* 1 when at least one thread is bound to a single core */
	int core_of[SERE_MACHINE_MAX_THREADS]; /* thread i's core (hwloc logical index), -1 when it is
											* not bound within one core; the first min(threads,
											* SERE_MACHINE_MAX_THREADS) entries are set */
	const char* version;				   /* sere_version() */
	const char* commit;					   /* the git commit the harness was built from (the Makefile's GIT_COMMIT) */
	const char* compiler;				   /* the compiler of the harness, e.g. "gcc 12.2.0" */
} sere_machine;

/* Reads the facts for a run with the given OpenMP thread count. The binding is what the
 * threads really have, asked of hwloc from inside a parallel region of that many threads
 * (the same OpenMP threads the kernels then use): after sere_topo_bind it lists one core per
 * thread; a thread whose CPU set is the whole machine (or that hwloc cannot ask) is unbound. */
void sere_machine_read( sere_machine* machine, int threads );

/* The binding as text: "unbound" when no thread is bound, else the core of each thread in
 * thread order, comma separated, "-" for a thread that is not ("0,1"). Returns out. */
const char* sere_machine_binding_text( const sere_machine* machine, char* out, size_t size );

/* Writes the JSON object member
 *
 *   <indent>"machine": {
 *   <indent>  "cpu": "AMD EPYC",
 *   <indent>  "simd": "AVX-512",
 *   <indent>  "threads": 2,
 *   <indent>  "binding": [0, 1],          (or "unbound"; null for a thread not bound to one core)
 *   <indent>  "cores": 2,
 *   <indent>  "version": "0.1.0",
 *   <indent>  "commit": "532ff950e867",
 *   <indent>  "compiler": "gcc 12.2.0"
 *   <indent>}
 *
 * with every string JSON-escaped and no comma or newline after the closing brace, so the
 * caller writes ",\n" or "\n" as its object needs. indent may be NULL (""). */
void sere_machine_json( FILE* f, const char* indent, int threads );

/* The same, from facts already read. */
void sere_machine_write_json( FILE* f, const char* indent, const sere_machine* machine );

#ifdef __cplusplus
}
#endif
