"""Jinja2 templates of the generated code (package data; see stt_codegen.codegen.render)."""
