"""``rmpc export c --controller FILE --out DIR``: a saved controller as C99 source.

The command reads a controller file written by ``ctrl.save(path)`` (:func:`rmpc.load`) and writes
``DIR/rmpc_controller.h`` and ``DIR/rmpc_controller.c`` with :func:`rmpc.export_c`; it prints
what it wrote (the files' sizes, the static memory, the status codes the step returns). A bad
file, a controller without a C export or an output folder that cannot be written end with
status 2 and a message naming what and why (the ``rmpc`` command's error handling).
"""

from __future__ import annotations

import argparse

__all__ = ["add_export_parser"]


def _cmd_export_c(args: argparse.Namespace) -> int:
    from rmpc import export_c, load
    from toolkit_common.errors import ControllerFileError, InvalidArgumentError

    try:
        controller = load(args.controller)
    except ControllerFileError as err:  # the option the user gave, with the file's own complaint
        raise InvalidArgumentError("--controller", err.expected, f"{err.found} ({err.argument})") from None
    result = export_c(controller, args.out)
    for path in result.paths:
        print(f"wrote {path} ({result.sizes[path.name]} bytes)")
    print(f"{result.controller}: RMPC_NX {result.nx}, RMPC_NU {result.nu}; static memory "
          f"{result.static_bytes} bytes ({result.table_bytes} of tables, {result.workspace_bytes} of "
          f"workspace); status codes {', '.join(str(code) for code in result.returns)}")
    return 0


def add_export_parser(sub: argparse._SubParsersAction, out_dir: type | object) -> None:
    """Add ``export c`` to the ``rmpc`` command's sub-commands (``out_dir``: the ``--out`` type)."""
    export = sub.add_parser("export", help="a saved controller as dependency-free C99 source",
                            description="Write a saved controller as code for flight software.")
    esub = export.add_subparsers(dest="export_command", required=True, metavar="{c}")
    c_parser = esub.add_parser(
        "c", help="C99: rmpc_controller.h and rmpc_controller.c",
        description="Read a controller saved with ctrl.save(FILE) and write DIR/rmpc_controller.h and "
        "DIR/rmpc_controller.c (C99, no allocation, libm only; docs/export_c.rst). Exit status: 0 "
        "written, 2 bad input (a damaged or foreign file, a controller without a C export, an output "
        "folder that cannot be written).",
    )
    c_parser.add_argument("--controller", required=True, metavar="FILE", help="a saved controller file")
    c_parser.add_argument("--out", required=True, type=out_dir, metavar="DIR", help="output directory")
    c_parser.set_defaults(func=_cmd_export_c)
