"""The symkin version, recorded in every generated file and manifest."""

__version__ = "0.1.0"
