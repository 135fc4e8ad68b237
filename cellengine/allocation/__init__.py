"""Task allocation for dual-arm lab cells (issue #5); the public entry is cellengine.allocate."""
