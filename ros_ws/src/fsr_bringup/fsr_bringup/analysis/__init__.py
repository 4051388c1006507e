"""Offline analysis of a recording: arrays (load), metrics, figures and a Markdown summary."""
