/* gimbal2axis.native._native: a Python extension only so that pip builds the C kernel (c_kernel/src/*.c)
 * with the package (setup.py); Python calls it through ctypes (gimbal2axis/native/__init__.py), so this
 * module is empty. It stays with the package, not in c_kernel/: it is CPython glue (Python.h), which
 * the kernel, linked into the FMUs and the native drivers, must not need. */
#include <Python.h>

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "_native", "the scene runner's C kernels, used through ctypes",
                                    -1, NULL, NULL, NULL, NULL, NULL};

PyMODINIT_FUNC PyInit__native(void) { return PyModule_Create(&module); }
