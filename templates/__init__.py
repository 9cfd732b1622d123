"""Package marker: lets setuptools ship the Jinja2 templates as package data."""
