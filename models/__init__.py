"""Scene presets (TOML files), installed as the package ``wetcloth.presets``."""
