"""The Roughness Studio: a local web app on the library (``roughness studio``; the ``studio`` extra, NiceGUI).

``app`` builds the app from the page list, ``sessions`` keeps each browser tab's state and files, ``jobs`` runs
slow work in the background, ``uploads`` checks and stores uploaded files, ``pages`` holds one module per page.
Every number the pages show comes from the library's public API; the studio only arranges it.
"""
