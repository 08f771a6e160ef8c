"""The single-degree-of-freedom test rig of thesis 4.2.1: one cylinder moving a load mass."""
