"""host.gnc: guidance (desired frame and rates) and the preprocessing of paper 001 section 4.2."""
