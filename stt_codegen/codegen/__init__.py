"""Code generation: C99 and Python controllers, test vectors, manifest (see generate.py)."""
