"""Saving and loading designed controllers: ``ctrl.save(path)`` and :func:`rmpc.load`.

:mod:`rmpc.io.format` is the file (envelope, version, checksum, atomic writes),
:mod:`rmpc.io.design` the design's JSON values and their checked reading,
:mod:`rmpc.io.saveable` the ``save`` method and :mod:`rmpc.io.registry` the kinds and ``load``.
``docs/save_load.rst`` describes the format field by field.
"""
