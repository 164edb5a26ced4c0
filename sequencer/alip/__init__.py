"""ALIP step-to-step NMPC footstep planner (seed 001): model, S2S maps, NLP, solvers, planner."""
