"""Named SequencerParams presets as TOML files (loaded by SequencerParams.preset)."""
