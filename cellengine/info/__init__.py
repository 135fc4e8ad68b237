"""The information layer: files in, immutable models and keypoints out."""
