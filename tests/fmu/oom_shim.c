/* Allocation-failure injection for tests/fmu/test_out_of_memory.cpp, loaded with LD_PRELOAD.
 *
 * Interposes the allocation functions of the C library and forwards them to glibc's own entry points
 * (__libc_malloc, ...), which sidesteps dlsym(RTLD_NEXT): dlsym itself allocates, and would recurse.
 * The FMU links libstdc++ statically, so its operator new reaches malloc through the PLT as well.
 * free is not interposed: blocks come from glibc either way.
 *
 * Nothing is counted or failed until the driver arms the shim (through dlsym(RTLD_DEFAULT, ...)), so
 * the loader, the C++ runtime and the driver's own set-up run untouched. */
#define _GNU_SOURCE
#include <errno.h>
#include <stddef.h>
#include <stdint.h>

extern void* __libc_malloc(size_t size);
extern void* __libc_calloc(size_t count, size_t size);
extern void* __libc_realloc(void* pointer, size_t size);
extern void* __libc_memalign(size_t alignment, size_t size);
extern void* __libc_valloc(size_t size);
extern void* __libc_pvalloc(size_t size);

#define EXPORT __attribute__((visibility("default")))

static int armed;               /* counting at all */
static long fail_at;            /* 1-based index of the first allocation to fail; 0: count only */
static int fail_persistently;   /* every allocation from fail_at on fails, not only that one */
static long allocations;        /* counted since the last arm */
static long failed_allocations; /* refused since the last arm */

/* Called at every refusal: `break oom_shim_refusal` in gdb stops where the failing allocation is made,
 * which is often far from where the program later crashes. */
EXPORT __attribute__((noinline)) void oom_shim_refusal(void) { __asm__ volatile(""); }

/* Whether this allocation is refused. Atomics: a host may allocate from several threads. */
static int refuse(void) {
    if (!__atomic_load_n(&armed, __ATOMIC_ACQUIRE)) return 0;
    const long index = __atomic_add_fetch(&allocations, 1, __ATOMIC_ACQ_REL);
    const int refused = fail_at > 0 && (index == fail_at || (fail_persistently && index > fail_at));
    if (refused) {
        __atomic_add_fetch(&failed_allocations, 1, __ATOMIC_ACQ_REL);
        oom_shim_refusal();
    }
    return refused;
}

/* Fails the n-th allocation from now (n >= 1), and with persistent != 0 every later one too; n = 0
 * only counts. */
EXPORT void oom_shim_arm(long n, int persistent) {
    __atomic_store_n(&armed, 0, __ATOMIC_RELEASE);
    fail_at = n;
    fail_persistently = persistent != 0;
    __atomic_store_n(&allocations, 0, __ATOMIC_RELEASE);
    __atomic_store_n(&failed_allocations, 0, __ATOMIC_RELEASE);
    __atomic_store_n(&armed, 1, __ATOMIC_RELEASE);
}

EXPORT void oom_shim_disarm(void) { __atomic_store_n(&armed, 0, __ATOMIC_RELEASE); }

/* Allocations requested since the last arm (refused ones included). */
EXPORT long oom_shim_count(void) { return __atomic_load_n(&allocations, __ATOMIC_ACQUIRE); }

EXPORT long oom_shim_failures(void) { return __atomic_load_n(&failed_allocations, __ATOMIC_ACQUIRE); }

EXPORT void* malloc(size_t size) {
    if (refuse()) {
        errno = ENOMEM;
        return NULL;
    }
    return __libc_malloc(size);
}

EXPORT void* calloc(size_t count, size_t size) {
    if (refuse()) {
        errno = ENOMEM;
        return NULL;
    }
    return __libc_calloc(count, size);
}

/* A refused realloc leaves the block as it was, as a real one does. */
EXPORT void* realloc(void* pointer, size_t size) {
    if (refuse()) {
        errno = ENOMEM;
        return NULL;
    }
    return __libc_realloc(pointer, size);
}

EXPORT void* reallocarray(void* pointer, size_t count, size_t size) {
    size_t bytes;
    if (__builtin_mul_overflow(count, size, &bytes)) {
        errno = ENOMEM;
        return NULL;
    }
    return realloc(pointer, bytes);
}

EXPORT void* memalign(size_t alignment, size_t size) {
    if (refuse()) {
        errno = ENOMEM;
        return NULL;
    }
    return __libc_memalign(alignment, size);
}

EXPORT void* aligned_alloc(size_t alignment, size_t size) { return memalign(alignment, size); }

EXPORT int posix_memalign(void** result, size_t alignment, size_t size) {
    if (alignment % sizeof(void*) != 0 || (alignment & (alignment - 1)) != 0) return EINVAL;
    if (refuse()) return ENOMEM;
    void* pointer = __libc_memalign(alignment, size);
    if (pointer == NULL) return ENOMEM;
    *result = pointer;
    return 0;
}

EXPORT void* valloc(size_t size) {
    if (refuse()) {
        errno = ENOMEM;
        return NULL;
    }
    return __libc_valloc(size);
}

EXPORT void* pvalloc(size_t size) {
    if (refuse()) {
        errno = ENOMEM;
        return NULL;
    }
    return __libc_pvalloc(size);
}
