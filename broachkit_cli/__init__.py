"""Command-line interface of broachkit."""
