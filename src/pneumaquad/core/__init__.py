"""The actuator core: pure physics, the compiled valve + cylinder kernel, its named data
layouts, the object layer over them, controllers and the fitted valve curves."""
