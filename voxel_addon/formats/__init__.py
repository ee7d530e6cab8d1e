"""Voxels in and out (issue 21): Minecraft Java regions (NBT, region files, block
mapping), MagicaVoxel .vox read and write, and the import/export of a world. The
decoders depend only on core; `load`/`save` use world and storage."""
