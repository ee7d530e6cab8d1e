"""The live view on Blender's gpu module."""
