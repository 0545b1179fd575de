"""Figures (matplotlib PNG) and the HTML report.

Figures are drawn on `matplotlib.figure.Figure` objects, never through pyplot, so that armkit
neither needs a screen nor changes the backend of a user's own session.
"""
