"""The physics layer of docs/design.md: math and astronomy (constants, time, ephemeris, frames, elements), physics (forces,
dynamics, the RK4 step, orbit representations and cycle means) and propulsion (the robotic arms, Katz's thrust
laws).  Pure functions of arrays; nothing here knows about scenarios, controllers or files."""
