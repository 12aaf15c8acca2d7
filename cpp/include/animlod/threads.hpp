// How many threads the core's parallel loops may run at once, process-wide.
//
// Every parallel loop of the core (AQEM's ranking and collapse halves, skinning, point-to-mesh
// distances, the motion re-fit's frames, ...) takes at most thread_limit() threads. A process
// that already runs several jobs side by side (a Dask worker per core, an engine's job system)
// sets it so that each job's loops do not take every core again. Results never depend on it.
#pragma once

namespace animlod {

// Caps the core's threads at `threads` (0: every hardware thread, the default). The environment
// variable ANIMLOD_THREADS, read once before the first call, sets the starting cap the same way
// (a value that is not a whole number is ignored). Safe to call from any thread; loops already
// running keep their threads.
void set_thread_limit(unsigned threads);

// The threads a parallel loop may take now: the cap, at most the hardware threads, at least 1.
unsigned thread_limit();

// True when ANIMLOD_THREADS is set, now, to something other than a whole number, which the
// starting cap ignores (for a caller that warns about it).
bool thread_environment_ignored();

}  // namespace animlod
