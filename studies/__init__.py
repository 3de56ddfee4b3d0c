"""Scripted studies: python -m studies.NAME, or ccopt study NAME."""
