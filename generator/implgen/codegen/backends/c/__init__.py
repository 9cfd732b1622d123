"""The C backend (backend.py)."""
