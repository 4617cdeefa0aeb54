"""File contracts between evalsuite's parts: one module per file that one part writes and another reads.

* :mod:`~evalsuite.contracts.manifest` — ``manifest.csv`` of rendered stimuli (written by
  :mod:`renderers.stimuli`, read by the study app);
* :mod:`~evalsuite.contracts.results` — ``results.csv`` of a study (written by the study app's export, read
  by ``evalsuite analyze``).

These modules import nothing from the parts that use them.
"""
