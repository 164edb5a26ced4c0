"""ALIP NMPC presets, one TOML per robot (loaded by sequencer.alip.AlipParams.preset)."""
