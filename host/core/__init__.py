"""host.core: conventions of the whole host: rotations (the one owner of attitude conventions), frames, constants, time."""
