"""The model: dice, shapes, pips, materials, planes and scenes as frozen data (no physics)."""
