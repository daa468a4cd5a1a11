"""The paper's figures, regenerated from reduced data and tables (matplotlib, no display)."""
