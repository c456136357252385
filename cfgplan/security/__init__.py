"""Transport security of a society: its keys, TLS with mutual authentication, access control.

:mod:`cfgplan.security.keys` makes a society's certificate authority and one
key and certificate per robot, device and operator tool (``cfgplan keys new``);
:mod:`cfgplan.security.zenoh_tls` turns a folder of them into the Zenoh
settings of one robot's session (``--keys DIR``). Neither is imported unless
keys are made or used: the ``cryptography`` package is needed only to make them.
"""
