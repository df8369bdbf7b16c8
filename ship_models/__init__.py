"""Vessel models for broachkit (plugins; registry to come)."""
