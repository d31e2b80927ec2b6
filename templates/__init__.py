"""Jinja2 templates of every file symkin emits (installed as ``symkin.templates``)."""
