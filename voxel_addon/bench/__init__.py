"""`python -m voxel_addon bench`: fixed, seeded measurements written to CSV and PNG plots. One module per area."""
