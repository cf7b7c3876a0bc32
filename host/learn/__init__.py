"""host.learn: optimal-control samples (CasADi/IPOPT on Dask), training of the network, the sweep."""
