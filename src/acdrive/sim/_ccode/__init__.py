"""The engine's C: the C of each part kind, generated from its kernels, and the generators of a
system's controller-chain C and plant C.

* ``_translate``, ``_kind_c``: the kernel language translated to C (a kind's step, its plant
  roles, the helpers they call);
* ``_kinds``: the C of each part kind, in registries keyed by the part's class (``CStep`` for a
  sampled part, ``PlantC`` for a continuous part or a modulator), generated on a kind's first
  look-up, built-in or a user's alike;
* ``_prelude``: the C text every generated file starts with (the real type, the math functions
  by precision, complex arithmetic);
* ``_helpers``: the helpers a generated file holds, those its code calls (no ``static``
  function left unused, a warning on clang);
* ``_chain``: a system's controller chains (its sampled parts, grouped by their wiring);
* ``_c_source``: the C99 header and source of the controller chains (``to_c``);
* ``_plant_source``: the C99 header and source of the plant, with acdrive's integrator
  (``to_plant_c``).

The native tier of the loop (``sim._native``) compiles this C and runs it in place of numba's
loop; the export (``acdrive.export``) writes the same text into files, FMUs and board builds. It
lives in ``sim``: the plant's C integrates with the engine's Runge-Kutta tableau
(``sim._integrators``) and the engine's native tier runs it; like the rest of the engine it
imports nothing of the export or of a drive (``tests/test_layers.py``).
"""
