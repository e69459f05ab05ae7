"""Analytic shapes, CSG and plug-ins: every one a distance oracle."""
