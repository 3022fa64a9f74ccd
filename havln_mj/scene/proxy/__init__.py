"""Graph proxies: buildings synthesised from a real navigation graph when its mesh is absent."""
