"""What tests in every folder share: the expected variable names, a Model Exchange host, the independent
reference model and its symbolic derivation, the cheap scene of runs whose physics does not matter
(Python); the C++ tests' headers (check.hpp, core_settings.hpp, fmu_loader.hpp, hybrid_test_systems.hpp;
tests/CMakeLists.txt puts this folder on their include path). Imported as `support.<module>`: pytest puts
tests/ on sys.path for tests/conftest.py."""
