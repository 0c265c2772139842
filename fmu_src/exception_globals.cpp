// The C++ runtime's per-thread exception bookkeeping, in static thread-local storage.
//
// libstdc++'s own copy (eh_globals.o of the static libstdc++.a) uses the global-dynamic TLS model:
// in a dlopen'ed object its block is allocated on a thread's first throw, and when that allocation
// fails glibc prints "cannot allocate memory for thread-local data: ABORT" and exits the host. The
// first throw is exactly what running out of memory causes (std::bad_alloc), so the definitions here
// take its place in the link: initial-exec TLS is set up when the shared object is loaded (a host
// without room gets a failed dlopen, not an abort later). The layout is the Itanium C++ ABI's
// __cxa_eh_globals, fixed since GCC 3; were libstdc++ to need anything else from eh_globals.o, the
// link would fail with a duplicate definition instead of misbehaving.
#include <cstddef>

#if defined(__GLIBCXX__) && defined(__linux__) && !defined(__ARM_EABI_UNWINDER__)
namespace __cxxabiv1 {
struct __cxa_exception;
struct __cxa_eh_globals {
    __cxa_exception* caughtExceptions;
    unsigned int uncaughtExceptions;
};
}  // namespace __cxxabiv1

namespace {
__thread __cxxabiv1::__cxa_eh_globals exception_globals __attribute__((tls_model("initial-exec")));
}

namespace __cxxabiv1 {
extern "C" __cxa_eh_globals* __cxa_get_globals() noexcept { return &exception_globals; }
extern "C" __cxa_eh_globals* __cxa_get_globals_fast() noexcept { return &exception_globals; }
}  // namespace __cxxabiv1
#endif
