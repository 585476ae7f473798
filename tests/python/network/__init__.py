"""Topics and services across hosts, in network namespaces."""
