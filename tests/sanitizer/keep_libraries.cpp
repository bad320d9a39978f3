// Linked into the command line only in sanitizer builds (PENUMBRA_SANITIZE), never shipped.
//
// The painter's GL driver (Mesa's swrast_dri.so, and the X and GL libraries GLFW opens) is
// unloaded when the window closes, and with it the globals that point at what the driver
// allocated. LeakSanitizer, which runs at exit, then reports those blocks as leaks, with the
// allocating frames in unmapped code that it cannot name, so no suppression can single out
// the driver without also hiding leaks of ours. Unloading nothing keeps the driver's memory
// reachable and its frames named: a real leak in it is matched by tests/lsan.supp by name,
// and one in our code still fails the tests.
// Replaces libc's for the whole process (the executable comes first in symbol lookup);
// <dlfcn.h> is left out so that its exception specification does not have to be matched.
extern "C" int dlclose(void*) {
  return 0;  // the library stays mapped until exit, as with RTLD_NODELETE
}
