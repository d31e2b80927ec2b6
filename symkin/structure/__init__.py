"""Structural analysis: mobility (seed eqs. 8.1-8.4) and topology synthesis (sec. 2.2.2)."""
