"""Drivers: one interface and one lifecycle; the simulated cell by default."""
