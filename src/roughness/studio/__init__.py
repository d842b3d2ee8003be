"""The Roughness Studio: a local web app on the library (``roughness studio``; the ``studio`` extra, NiceGUI).

``app`` builds the app from the page list, ``sessions`` keeps each browser tab's files, ``jobs`` runs slow work in
the background (``job_panel`` shows it, ``work`` holds the jobs), ``uploads`` checks and stores uploaded files.
The parts pages share: ``texture_source`` (open or make a texture), ``feel_view`` and ``pictures`` (V, the
heightmap, its relief, the standard scale), ``compare_panel`` and ``downloads``. ``pages`` holds one module per
page. Every number the pages show comes from the library's public API; the studio only arranges it.
"""
