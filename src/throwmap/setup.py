from setuptools import find_packages, setup

package_name = 'throwmap'

setup(
    name=package_name,
    version='0.1.0',
    packages=find_packages(exclude=['test']),
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + package_name]),
        ('share/' + package_name, ['package.xml']),
    ],
    install_requires=['setuptools', 'numpy', 'pyyaml', 'matplotlib', 'numba'],
    zip_safe=False,
    maintainer='feeder team',
    maintainer_email='feeder@example.com',
    description='Throw map of a dynamic parts feeder (ROS-free library and CLI)',
    license='Apache-2.0',
    extras_require={'test': ['pytest', 'hypothesis', 'scipy'],
                    'cluster': ['dask', 'distributed']},
    entry_points={'console_scripts': ['throwmap = throwmap.cli:main']},
)
