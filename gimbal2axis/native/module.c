/* gimbal2axis.native._native: a Python extension only so that pip builds the C kernels with the package
 * (setup.py); Python calls them through ctypes (gimbal2axis/native/__init__.py), so this module is empty. */
#include <Python.h>

static struct PyModuleDef module = {PyModuleDef_HEAD_INIT, "_native", "the scene runner's C kernels, used through ctypes",
                                    -1, NULL, NULL, NULL, NULL, NULL};

PyMODINIT_FUNC PyInit__native(void) { return PyModule_Create(&module); }
