"""The physical checks of a motion on the humanoid: kinematic validity per frame (joint
range, self-contact, floor), contact queries, the inverse-dynamics residual, and the
kinematic checker the ``feasible`` transition method is given."""
