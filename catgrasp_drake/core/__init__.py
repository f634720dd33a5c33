"""Numerical core: CPD, shape space, latent inference, deformation fields.

Imports only numpy and scipy (a test enforces it). Point sets are ``(N, 3)``
float arrays in metres.
"""
