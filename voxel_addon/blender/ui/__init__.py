"""Sidebar panels and operators, one module per section; see blender/__init__.py."""
