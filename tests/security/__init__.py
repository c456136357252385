"""Transport security of a society: keys, TLS with mutual authentication, access control."""
