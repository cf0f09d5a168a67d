"""wetcloth.exporter: Blender-ready mesh sequences (PLY, OBJ, USD) of a simulated cloth."""
