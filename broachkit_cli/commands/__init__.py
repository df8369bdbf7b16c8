"""Sub-commands of the ``broachkit`` command line."""
