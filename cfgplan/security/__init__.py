"""Security of a society: its keys, TLS with mutual authentication, access control,
bounded input.

:mod:`cfgplan.security.keys` makes a society's certificate authority and one
key and certificate per robot, device and operator tool (``cfgplan keys new``),
:mod:`cfgplan.security.renew` one member's next key (``cfgplan keys renew``);
:mod:`cfgplan.security.zenoh_tls` turns a folder of them into the Zenoh
settings of one robot's session (``--keys DIR``). None of these is imported
unless keys are made or used: the ``cryptography`` package is needed only to
make them. Every robot on the network, with keys or without, uses
:mod:`cfgplan.security.rates` (a flood on a channel is cut to its allowance)
and :mod:`cfgplan.security.identity` (two problems under one society name
refuse each other): pure Python, light to import.
"""
