"""The studio's pages, one module each (``PATH``, ``TITLE``, ``SUMMARY``, ``build(session)``), listed in
``roughness.studio.app.PAGES``."""
