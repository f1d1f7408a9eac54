"""Output: mesh frames, pictures, run summaries and the checks reported in them."""
