"""Syntax: the Lark grammar, the reader into the IR, the printer back, and diagnostics."""
