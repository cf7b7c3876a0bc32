"""Cycle model, setup and benchmark scripts."""
