"""Build of the C core's extension module (the rest of the package is in pyproject.toml).

``_lmi_ccore`` is the interior-point method of ``lmi/ccore/ipm.c`` compiled with
``-DKOTHARE_RUNTIME`` (the problem given at run time, see ``lmi/ccore/runtime.h``): the same
source an exported controller compiles, called by :mod:`lmi.ccore.runtime` through ctypes. It is
a top-level module so that a test run from the checkout (whose ``lmi`` shadows the installed
one) finds the installed build; its ``SOURCE_HASH`` lets the package refuse a build older than
its C sources. The build is optional: without a C compiler the install still succeeds and the
solver runs its numba kernels (:mod:`lmi.ipm.kernels`).

Flags: ``-std=c99`` as the exports are compiled (no contraction into fused multiply-adds, so the
answers are those of an export's ``-O2`` build bit for bit), ``-O3`` and ``-march=native`` where
the compiler takes them (measured on paper P's satellite at 2 vertices: 5.0 ms per warm solve at
``-O2``, 4.3 ms at ``-O3``, 3.7 ms with both; numba's kernels 4.7 ms). ``RMPC_CORE_PORTABLE=1``
leaves ``-march=native`` out (a build to copy to other machines).
"""

import hashlib
import os
import tempfile
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

CORE = Path("lmi") / "ccore"
#: the files whose bytes make the source hash, in this order (lmi.ccore.runtime.HASHED_SOURCES)
HASHED_SOURCES = ("dense.c", "dense.h", "ipm.c", "ipm.h", "runtime.h", "module.c")


def source_hash() -> str:
    digest = hashlib.sha256()
    for name in HASHED_SOURCES:
        digest.update((CORE / name).read_bytes())
    return digest.hexdigest()


class BuildCore(build_ext):
    """``build_ext`` adding the optimisation flags the compiler accepts."""

    def build_extensions(self) -> None:
        wanted = ["-O3"] + ([] if os.environ.get("RMPC_CORE_PORTABLE") == "1" else ["-march=native"])
        flags = [flag for flag in wanted if self._accepts(flag)]
        for ext in self.extensions:
            ext.extra_compile_args = [*ext.extra_compile_args, *flags]
        super().build_extensions()

    def _accepts(self, flag: str) -> bool:
        with tempfile.TemporaryDirectory() as tmp:
            probe = Path(tmp) / "probe.c"
            probe.write_text("int main(void) { return 0; }\n")
            try:
                self.compiler.compile([str(probe)], output_dir=tmp, extra_postargs=[flag])
            except Exception:  # a CompileError or a missing compiler: leave the flag out
                return False
        return True


setup(
    cmdclass={"build_ext": BuildCore},
    ext_modules=[
        Extension(
            "_lmi_ccore",
            sources=[str(CORE / name) for name in ("module.c", "ipm.c", "dense.c")],
            define_macros=[("KOTHARE_RUNTIME", None), ("KOTHARE_SOURCE_HASH", f'"{source_hash()}"')],
            extra_compile_args=["-std=c99", "-O2"],
            optional=True,
        )
    ],
)
