"""Foundations shared by every layer: signal declarations and compiled table lookup."""
