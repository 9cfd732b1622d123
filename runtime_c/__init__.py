"""Package marker: lets setuptools ship the C runtime sources as package data."""
