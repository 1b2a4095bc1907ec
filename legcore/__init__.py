"""LegOpt core: kinematics, dynamics, trajectories, problems and optimisers (pure library)."""
