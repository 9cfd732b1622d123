"""The Python backend (backend.py)."""
