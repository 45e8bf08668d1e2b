twoball sweep twoball/precomputed/contacts.zarr --eps 0.816 --mu 1e-4:1:161:log --tau-ratio 1e-4:1:161:log --chunks 1,20,161 --dtype float32
