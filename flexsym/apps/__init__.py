"""Layer 9, apps: the user's entry points, the command line (`flexsym`) and the Python API."""
