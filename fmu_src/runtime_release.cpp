// Each dlopen/dlclose of the FMU would otherwise leak the emergency exception-handling pool of the
// statically linked C++ runtime (72,704 bytes, allocated when the shared object is loaded and never
// freed). libstdc++ offers __gnu_cxx::__freeres() for exactly this; it runs when the shared object is
// unloaded, after the last fmi2* call can have thrown.
#include <cstddef>

#if defined(__GLIBCXX__)
namespace __gnu_cxx {
void __freeres() noexcept;
}

__attribute__((destructor)) static void release_cxx_runtime_pool() { __gnu_cxx::__freeres(); }
#endif
