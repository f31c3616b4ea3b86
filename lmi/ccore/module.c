/* The Python extension module _lmi_ccore: the C core built with -DKOTHARE_RUNTIME (ipm.c,
 * dense.c) in a module that `pip install .` compiles (setup.py). The module holds no Python
 * functions: lmi.ccore.runtime calls the kothare_rt_* functions of runtime.h through ctypes on
 * this module's file. SOURCE_HASH is the SHA-256 of the C sources it was built from (setup.py
 * passes it), so that the package can tell a build older than its sources. */
#define PY_SSIZE_T_CLEAN
#include <Python.h>

#ifndef KOTHARE_SOURCE_HASH
#define KOTHARE_SOURCE_HASH "unknown"
#endif

static struct PyModuleDef core_module = {
    PyModuleDef_HEAD_INIT, "_lmi_ccore",
    "The C core of the toolkit's interior-point method (see lmi.ccore.runtime).", -1,
    NULL, NULL, NULL, NULL, NULL,
};

PyMODINIT_FUNC PyInit__lmi_ccore(void)
{
    PyObject *module = PyModule_Create(&core_module);
    if (module != NULL && PyModule_AddStringConstant(module, "SOURCE_HASH", KOTHARE_SOURCE_HASH) != 0) {
        Py_DECREF(module);
        return NULL;
    }
    return module;
}
