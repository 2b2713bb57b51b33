"""Bags: reading the node's inputs, replaying them through the core, outputs and fleets."""
