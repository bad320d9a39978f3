// What `render` shows while a progressive method (a path tracer, 2D or 3D) runs, and its Ctrl-C.
#pragma once

#include <atomic>

#include "penumbra/progress.hpp"

// Set by the first Ctrl-C while watch_interrupts() is on: the method stops after the current
// pass (the image of the samples so far is still written); a second Ctrl-C ends the process.
extern std::atomic<bool> g_cancel;

// Installs the Ctrl-C handler (on) or restores the default (off).
void watch_interrupts(bool on);

// A one-line progress bar with an estimate of the time left, redrawn in place on stderr.
void draw_progress(const penumbra::RenderProgress& p);
